#!/usr/bin/env bash
# test_study_adaptive_browser.sh — the adaptive design through the real participant page in Chromium (issue 28): a
# study designed with --adaptive --trials 4 (one scene x camera path, T = 2, 4, 8, 16), a participant answering every
# trial by keyboard and reloading midway (the same trial comes back), every answer stored once; the T of each trial
# chosen by the server: the same answers sent to a second study of the same design and seed without any page give
# the same trials with the same T (study_adaptive.mjs).
# Usage: test_study_adaptive_browser.sh TASLAB_BINARY WORK_DIR
source "$(dirname "$0")/common.sh"
mkdir -p "$work/stimuli/calm-still/clips"
"$taslab" render --scene turntable --frames 0:6 --size 64x36 --device lavapipe --quiet --no-exr --out "$work/run" >/dev/null
"$taslab" clip "$work/run" --out "$work/clip.webm" 2>/dev/null
for c in ref tfr-T2 tfr-T4 tfr-T8 tfr-T16; do cp "$work/clip.webm" "$work/stimuli/calm-still/clips/$c.webm"; done
cat > "$work/stimuli/calm-still/pairs.json" <<JSON
{"taslab_pairs": 1, "scene": "calm", "camera": "still", "camera_motion": "stationary", "fps": 60, "frames": [0, 5],
 "reference": {"clip": "clips/ref.webm", "method": "ref"},
 "conditions": [{"method": "tfr", "T": 2, "clip": "clips/tfr-T2.webm"}, {"method": "tfr", "T": 4, "clip": "clips/tfr-T4.webm"},
  {"method": "tfr", "T": 8, "clip": "clips/tfr-T8.webm"}, {"method": "tfr", "T": 16, "clip": "clips/tfr-T16.webm"}]}
JSON
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done' EXIT
for s in study replay; do
  "$taslab" study design --db "$work/$s.db" --stimuli "$work/stimuli" --participants 2 --seed 3 --catch 1 \
    --adaptive --trials 4 >/dev/null
  "$taslab" study serve --db "$work/$s.db" --port 0 > "$work/$s.out" 2>&1 &
  pids+=($!)
done
args=()
for s in study replay; do
  for _ in $(seq 100); do grep -q "admin token" "$work/$s.out" 2>/dev/null && break; sleep 0.1; done
  args+=("$(grep -o 'http://127.0.0.1:[0-9]*' "$work/$s.out" | head -1)")
  args+=("$("$taslab" study links --db "$work/$s.db" | head -1 | sed 's|.*/p/||')")
  args+=("$(grep -o 'admin token [0-9a-f]*' "$work/$s.out" | cut -d' ' -f3)")
done
node "$here/study_adaptive.mjs" "${args[@]}"
echo "1 passed, 0 failed"
