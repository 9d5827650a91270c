#!/usr/bin/env bash
# test_study_stereo_browser.sh — stereo study clips end to end (issue 25, STEREO.md "studies add display=stereo"):
# `taslab pair --stereo` writes side-by-side clips (2W x H) and pairs.json "display": "stereo"; a study of stereo sets
# serves "display": "stereo" and its participant page shows each clip at full width with the eyes' halves labelled
# (checked in Chromium, with a screenshot in WORK_DIR/stereo_page.png); a stereo set and a mono set in one study are
# refused with one line.
# Usage: test_study_stereo_browser.sh TASLAB_BINARY WORK_DIR
source "$(dirname "$0")/common.sh"
scene="$here/../data/stereo_plane.json"
"$taslab" pair --scene "$scene" --frames 0:8 --fps 8 --size 48x32 --stereo --ipd 0.3 --variants ref,sa --device lavapipe \
  --out "$work/stimuli/st" >/dev/null 2>&1
grep -q '"display": "stereo"' "$work/stimuli/st/pairs.json" || { echo "pairs.json without display stereo"; exit 1; }
grep -Eq '"ipd": 0\.(3|2999999)' "$work/stimuli/st/pairs.json" || { echo "pairs.json without the ipd"; exit 1; }
# the inspection clip: the reference's side-by-side frames above the variant's
"$taslab" study design --db "$work/study.db" --stimuli "$work/stimuli" --participants 1 --seed 3 --catch 0 --training 0 \
  >/dev/null
"$taslab" study serve --db "$work/study.db" --port 0 > "$work/serve.out" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 50); do grep -q "admin token" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
base=$(grep -o 'http://127.0.0.1:[0-9]*' "$work/serve.out" | head -1)
code=$("$taslab" study links --db "$work/study.db" | head -1 | sed 's|.*/p/||')
node "$here/study_stereo.mjs" "$base" "$code" "$work/stereo_page.png"
kill $server 2>/dev/null || true
# a mono set beside the stereo one: one line, exit 2, no study
mkdir -p "$work/stimuli/mono/clips"
cp "$work/stimuli/st/clips/ref.webm" "$work/stimuli/mono/clips/ref.webm"
cat > "$work/stimuli/mono/pairs.json" <<JSON
{"taslab_pairs": 1, "scene": "s", "camera": "c", "camera_motion": "stationary", "fps": 8, "frames": [0, 7],
 "reference": {"clip": "clips/ref.webm"}, "conditions": [{"method": "ref", "clip": "clips/ref.webm"}]}
JSON
set +e
out=$("$taslab" study design --db "$work/mixed.db" --stimuli "$work/stimuli" --participants 1 2>&1)
rc=$?
set -e
if [ "$rc" != 2 ] || [ "$(printf '%s\n' "$out" | wc -l)" != 1 ] || ! grep -q "a stereo set in a study of mono sets" <<<"$out"; then
  echo "mixed stereo and mono sets: exit $rc, printed: $out"; exit 1
fi
echo "1 passed, 0 failed"
