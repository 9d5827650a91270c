#!/usr/bin/env bash
# test_report_browser.sh — the sweep report in Debian's Chromium (ctest): a tiny sweep (turntable/orbit, ref, tfr@8,
# rrc/4, 48 frames at 48x32), then report/index.html opened from disk (file://, network off): no failed request, no
# console error, every plot and thumbnail loads, the first clip pair plays and stays in sync (report_check.mjs). Two
# negative controls: a plot removed, and the variant clip played 10% fast (drift and resyncs), must each fail.
# Usage: test_report_browser.sh TASLAB_BINARY WORK_DIR
source "$(dirname "$0")/common.sh"
"$taslab" sweep --scenes turntable --cameras orbit --variants ref,tfr@8,rrc/4 --frames 0:48 --size 48x32 \
  --device lavapipe --validation --quiet --out "$work/sw" >/dev/null
node "$here/report_check.mjs" "$work/sw/report/index.html" 7 "$work/report.png"
echo "negative control (the variant clip played 10% fast drifts a frame every 0.17 s: resyncs must be too many):"
if neg=$(RATE=1.1 node "$here/report_check.mjs" "$work/sw/report/index.html" 7 2>&1); then
  echo "$neg"; echo "negative control passed: the sync check cannot fail"; exit 1
fi
echo "$neg"
grep -qE 'FAIL (.* resyncs in|clips out of sync)' <<<"$neg" || { echo "negative control failed for another reason"; exit 1; }
echo "negative control (a plot file removed must be found):"
rm "$work/sw/report/plots/turntable--orbit--flip.svg"
if node "$here/report_check.mjs" "$work/sw/report/index.html" 7; then
  echo "negative control passed: the check cannot fail"; exit 1
fi
echo "1 passed, 0 failed"
