#!/usr/bin/env bash
# test_study_telemetry_browser.sh — remote participants' playback telemetry in Chromium (issue 28): real playbacks of
# 200 ms clips record plausible durations and frame counts; a trial whose page is hidden while its clips play and one
# whose playback stalls (played at 1/16 speed) are stored, not counted, and come again (study_telemetry.mjs).
# Usage: test_study_telemetry_browser.sh TASLAB_BINARY WORK_DIR
source "$(dirname "$0")/common.sh"
mkdir -p "$work/stimuli/calm-still/clips"
"$taslab" render --scene turntable --frames 0:12 --size 64x36 --device lavapipe --quiet --no-exr --out "$work/run" >/dev/null
"$taslab" clip "$work/run" --out "$work/clip.webm" 2>/dev/null
for c in ref tfr-T8 tfr-T16; do cp "$work/clip.webm" "$work/stimuli/calm-still/clips/$c.webm"; done
cat > "$work/stimuli/calm-still/pairs.json" <<JSON
{"taslab_pairs": 1, "scene": "calm", "camera": "still", "camera_motion": "stationary", "fps": 60, "frames": [0, 11],
 "reference": {"clip": "clips/ref.webm", "method": "ref"},
 "conditions": [{"method": "tfr", "T": 8, "clip": "clips/tfr-T8.webm"}, {"method": "tfr", "T": 16, "clip": "clips/tfr-T16.webm"}]}
JSON
"$taslab" study design --db "$work/study.db" --stimuli "$work/stimuli" --participants 1 --seed 4 --catch 1 >/dev/null
"$taslab" study serve --db "$work/study.db" --port 0 > "$work/serve.out" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q "admin token" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
base=$(grep -o 'http://127.0.0.1:[0-9]*' "$work/serve.out" | head -1)
token=$(grep -o 'admin token [0-9a-f]*' "$work/serve.out" | cut -d' ' -f3)
code=$("$taslab" study links --db "$work/study.db" | head -1 | sed 's|.*/p/||')
node "$here/study_telemetry.mjs" "$base" "$code" "$token" 200
grep -Eq "answered trial 0 with a broken playback \(([a-z]+;)*hidden(;[a-z]+)*\)" "$work/serve.out" || { echo "no log line for the hidden trial"; exit 1; }
echo "1 passed, 0 failed"
