#!/usr/bin/python3
# make_study_ratings.py — a deterministic synthetic ratings file in taslab's long format (DESIGN section 7)
# for the study statistics tests: 12 participants x method tfr x T 8, 16 x 3 scenes x 2 camera paths
# (stationary "still", moving "walk"), one rating each; effects of T, scene and camera built in, plus noise
# from a fixed LCG (period empty: tfr has none). The R script study_reference.R computes the reference statistics
# from this file.
seed = 12345
def rnd():
    global seed
    seed = (seed * 1103515245 + 12345) % 2**31
    return seed / 2**31
print("participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms")
scenes = {"calm": 0.6, "moderate": 0.2, "dynamic": -0.1}
for p in range(1, 13):
    trial = 0
    bias = rnd() - 0.5
    for T, tb in ((8, -0.3), (16, 0.6)):
        for sc, sb in scenes.items():
            for cam, motion, cb in (("still", "stationary", 0.3), ("walk", "moving", -0.2)):
                x = tb + sb + cb + bias + (rnd() - 0.5) * 2.2
                r = max(-2, min(2, round(x)))
                ref_first = (p + trial) % 2
                answer = -r if ref_first else r
                print(f"P{p:02d},{trial},{sc},{cam},{motion},tfr,{T},,{ref_first},{answer},{r},{int(800 + rnd() * 3000)}")
                trial += 1
