#!/usr/bin/env bash
# test_study_recovery_browser.sh — the participant page and the server under failure (issue 27), in Chromium with
# the server killed and restarted under the test (study_recovery.mjs): the server down when Continue is pressed after a
# break (no answer panel until this trial's clips played), killed during a clip download (a visible retry message,
# recovery by itself, the message gone afterwards), one link in two browser contexts (the window taken over is told
# and stores nothing), both clips of every trial at one byte length and no trial kind but training in the trial JSON,
# the server's log lines, a second server on the same study refused, and the live status page (screenshot
# status.png in WORK_DIR) with each participant's P.910-crowd flags and broken playbacks (issue 28).
# Usage: test_study_recovery_browser.sh TASLAB_BINARY WORK_DIR
source "$(dirname "$0")/common.sh"
mkdir -p "$work/stimuli"
# Clips of different byte lengths: the reference 8 frames, the test clips 5 (the network tab must not tell them apart).
"$taslab" render --scene turntable --frames 0:8 --size 64x36 --device lavapipe --quiet --no-exr --out "$work/run8" >/dev/null
"$taslab" render --scene turntable --frames 0:5 --size 64x36 --device lavapipe --quiet --no-exr --out "$work/run5" >/dev/null
"$taslab" clip "$work/run8" --out "$work/ref.webm" 2>/dev/null
"$taslab" clip "$work/run5" --out "$work/test.webm" 2>/dev/null
for set in calm-still:calm:still:stationary calm-walk:calm:walk:moving; do
  IFS=: read -r name scene camera motion <<<"$set"
  mkdir -p "$work/stimuli/$name/clips"
  cp "$work/ref.webm" "$work/stimuli/$name/clips/ref.webm"
  for c in tfr-T8 tfr-T16; do cp "$work/test.webm" "$work/stimuli/$name/clips/$c.webm"; done
  cat > "$work/stimuli/$name/pairs.json" <<JSON
{"taslab_pairs": 1, "scene": "$scene", "camera": "$camera", "camera_motion": "$motion", "fps": 60, "frames": [0, 7],
 "reference": {"clip": "clips/ref.webm", "method": "ref"},
 "conditions": [{"method": "tfr", "T": 8, "clip": "clips/tfr-T8.webm"}, {"method": "tfr", "T": 16, "clip": "clips/tfr-T16.webm"}]}
JSON
done
cmp -s "$work/ref.webm" "$work/test.webm" && { echo "the reference and test clips must differ in size"; exit 1; }
"$taslab" study design --db "$work/study.db" --stimuli "$work/stimuli" --participants 2 --seed 5 --catch 1 --gold 1 --training 1 \
  --break-every 2 >/dev/null
node "$here/study_recovery.mjs" "$taslab" "$work/study.db" "$work"
echo "1 passed, 0 failed"
