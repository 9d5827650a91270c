# common.sh — sourced by the browser test scripts: arguments, environment and prerequisites.
# Sets taslab (the binary), work (a fresh work folder) and here (this folder).
set -euo pipefail
taslab="$1" work="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export ASAN_OPTIONS=detect_leaks=0 # the ASan build's driver leak (tests/lsan.supp) is not ours
[ -x /usr/bin/chromium ] || { echo "chromium is not installed: run scripts/setup"; exit 1; }
[ -d "$here/node_modules/playwright-core" ] || { echo "playwright-core is not installed: run scripts/setup"; exit 1; }
rm -rf "$work" && mkdir -p "$work"
