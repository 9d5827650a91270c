# require.sh — sourced by the shell tests: `require WHAT COMMAND...` runs COMMAND (a check); when it fails, the
# prerequisite WHAT is missing. Under CI (CI set and non-empty) that fails the test (exit 1): a test that passes
# when what it tests is absent proves nothing. Outside CI the test is skipped with "SKIPPED: WHAT" and exit 77
# (ctest's SKIP_RETURN_CODE, tests/CMakeLists.txt). The shell form of tu_require in test_util.h.
require() {
  local what="$1"
  shift
  "$@" && return 0
  if [ -n "${CI:-}" ]; then
    echo "missing prerequisite (CI is set, so this fails instead of skipping): $what"
    exit 1
  fi
  echo "SKIPPED: $what"
  exit 77
}
