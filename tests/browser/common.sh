# common.sh — sourced by the browser test scripts: arguments, environment and prerequisites.
# Sets taslab (the binary), work (a fresh work folder) and here (this folder). A missing prerequisite fails under CI
# and skips (exit 77, saying what) outside (require.sh).
set -euo pipefail
taslab="$1" work="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source "$here/../lsan_env.sh"
source "$here/../require.sh"
require "$(basename "$0"): chromium is not installed (run scripts/setup)" test -x "${CHROMIUM:-/usr/bin/chromium}"
require "$(basename "$0"): playwright-core is not installed (run scripts/setup)" test -d "$here/node_modules/playwright-core"
rm -rf "$work" && mkdir -p "$work"
