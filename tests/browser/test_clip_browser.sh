#!/usr/bin/env bash
# test_clip_browser.sh — browser fidelity test (ctest): render a short run, encode its clip, and check in
# Debian's Chromium that chosen frames drawn from the <video> equal the PNG frames exactly (max difference 0).
# A negative control compares each frame with its neighbour's PNG and must find differences, so the
# comparison can fail. Usage: test_clip_browser.sh TASLAB_BINARY WORK_DIR
source "$(dirname "$0")/common.sh"
"$taslab" render --scene turntable --camera orbit --frames 30:42 --size 96x54 --device lavapipe --quiet --out "$work/run" >/dev/null
"$taslab" clip "$work/run" --out "$work/clip.webm" 2>/dev/null
node "$here/clip_fidelity.mjs" "$work/clip.webm" "$work/run/frames" 60 30 30,31,36,41
echo "negative control (frames compared with their neighbours' PNGs):"
if node "$here/clip_fidelity.mjs" "$work/clip.webm" "$work/run/frames" 60 31 32,37; then
  echo "negative control found no difference: the comparison cannot fail"; exit 1
fi
echo "1 passed, 0 failed"
