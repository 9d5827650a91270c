#!/usr/bin/env bash
# test_study_browser.sh — browser end-to-end test of the study (ctest): a participant completes a session in
# Chromium, reloading midway; every answer must be in the database exactly once.
# Usage: test_study_browser.sh TASLAB_BINARY WORK_DIR
source "$(dirname "$0")/common.sh"
mkdir -p "$work/stimuli"
"$taslab" render --scene turntable --frames 0:6 --size 64x36 --device lavapipe --quiet --no-exr --out "$work/run" >/dev/null
"$taslab" clip "$work/run" --out "$work/clip.webm" 2>/dev/null
for set in calm-still:calm:still:stationary calm-walk:calm:walk:moving; do
  IFS=: read -r name scene camera motion <<<"$set"
  mkdir -p "$work/stimuli/$name/clips"
  for c in ref tfr-T8 tfr-T16; do cp "$work/clip.webm" "$work/stimuli/$name/clips/$c.webm"; done
  cat > "$work/stimuli/$name/pairs.json" <<JSON
{"taslab_pairs": 1, "scene": "$scene", "camera": "$camera", "camera_motion": "$motion", "fps": 60, "frames": [0, 5],
 "reference": {"clip": "clips/ref.webm"},
 "conditions": [{"method": "tfr", "T": 8, "clip": "clips/tfr-T8.webm"}, {"method": "tfr", "T": 16, "clip": "clips/tfr-T16.webm"}]}
JSON
done
"$taslab" study design --db "$work/study.db" --stimuli "$work/stimuli" --participants 1 --seed 3 --catch 1 --training 1 \
  --break-every 3 >/dev/null
"$taslab" study serve --db "$work/study.db" --port 0 > "$work/serve.out" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 50); do grep -q "admin token" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
base=$(grep -o 'http://127.0.0.1:[0-9]*' "$work/serve.out" | head -1)
token=$(grep -o 'admin token [0-9a-f]*' "$work/serve.out" | cut -d' ' -f3)
code=$("$taslab" study links --db "$work/study.db" | head -1 | sed 's|.*/p/||')
node "$here/study_session.mjs" "$base" "$code" "$token" 4
echo "1 passed, 0 failed"
