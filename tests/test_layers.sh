#!/usr/bin/env bash
# test_layers.sh — the dependency rules inside the renderer (ARCHITECTURE.md), which one library target
# cannot enforce by itself: device/ includes nothing above it; frame/ not passes/ or methods/; passes/ not
# methods/ or analysis/; only render.c and run_render.c (the composition root) see everything. Across
# libraries the build enforces the rules (include paths, the poisoned vulkan.h); this also checks that no
# library includes the CLI header and no library calls exit(); no method name in study/ or metrics/ (30.1) and no
# source or test file above 1,000 lines (30.6); no bare negative return in a library (30.5).
set -u
cd "$(dirname "$0")/.."
bad=0
check() { # check DIR PATTERN WHAT
  local hits
  hits=$(grep -rnE "$2" "$1" --include=*.c --include=*.h --include=*.cpp 2>/dev/null)
  if [ -n "$hits" ]; then echo "layer rule broken ($3):"; echo "$hits" | sed 's/^/  /'; bad=1; fi
}
check renderer/src/device '#include "\.\./(frame|passes|methods|analysis)/' "device/ must not include the layers above it"
check renderer/src/frame '#include "\.\./(passes|methods|analysis)/' "frame/ must not include passes/, methods/, analysis/"
check renderer/src/passes '#include "\.\./(methods|analysis)/' "passes/ must not include methods/ or analysis/"
check renderer/src/methods '#include "\.\./analysis/' "methods/ must not include analysis/"
check renderer/src/frame 'extern const render_method ' "frame/ names no method (methods/registry.c is the only list, issue 30.1)"
for lib in scenes renderer/base renderer/output renderer/src metrics/src study/src; do
  check "$lib" '#include "(cli|commands)\.h"' "a library including the CLI header"
  check "$lib" '(^|[^_a-z])exit\(' "exit() in a library (return a tl_err instead)"
done
check scenes '#include "taslab/(render|vkdev|run|metrics|study)' "scenes/ sees only base"
check renderer/output '#include "taslab/(render|vkdev|scene|metrics|study|method)' "output/ sees only base"
check metrics/src '#include "taslab/(render|vkdev|analyze|method|study)' "metrics/ sees only output and base"
# Issue 30.5: one error enum. A library function returns TL_OK or a tl_err code (tl_error.h), never a bare negative
# number; a helper whose -1 is an index or "not found" (turned into a code by its caller) says "local sentinel" there.
for lib in scenes renderer/base renderer/output renderer/src metrics/src study/src; do
  hits=$(grep -rnE 'return -[0-9]+;' "$lib" --include=*.c --include=*.h --include=*.cpp 2>/dev/null | grep -v "local sentinel")
  if [ -n "$hits" ]; then echo "layer rule broken (a bare negative return in $lib: return a tl_err code):"; echo "$hits" | sed 's/^/  /'; bad=1; fi
done
# Issue 30.1: knowledge about methods lives only in the method registry. The study and metrics libraries read what
# they need from manifest.json and pairs.json (method_facts), so no method name of the registry's METHODS list (or a
# -FLAG form of one, tarc-oracle) appears there as a string literal; a line using such a word for something else
# says "not a method name".
names=$(sed -n 's/^[[:space:]]*X(\([a-z0-9_]*\)).*/\1/p' renderer/src/methods/registry.c | paste -sd'|' -)
if [ -z "$names" ]; then echo "layer rule broken: no METHODS list in renderer/src/methods/registry.c"; bad=1; fi
for lib in study/src study/include metrics/src metrics/include; do
  hits=$(grep -rnE "\"($names)(-[a-z]+)?\"" "$lib" --include=*.c --include=*.h 2>/dev/null | grep -v "not a method name")
  if [ -n "$hits" ]; then echo "layer rule broken (a method name in $lib: read method_facts instead):"; echo "$hits" | sed 's/^/  /'; bad=1; fi
done
# Issue 30.6: no source or test file above 1,000 lines (CONVENTIONS: a file is one concern a reader can hold; split
# by concern before it grows past this). Generated files and third-party data are not in git's source list.
long=$(git ls-files -- '*.c' '*.h' '*.cpp' '*.glsl' '*.in' '*.js' '*.sh' '*.py' 2>/dev/null | xargs -r wc -l 2>/dev/null |
	awk '$2 != "total" && $1 > 1000 {print "  " $2 ": " $1 " lines"}')
if [ -z "$(git ls-files -- CMakeLists.txt 2>/dev/null)" ]; then echo "layer rule broken: not a git checkout (the line-limit rule needs git ls-files)"; bad=1; fi
if [ -n "$long" ]; then echo "layer rule broken (a file above 1,000 lines: split it by concern):"; echo "$long"; bad=1; fi
[ $bad = 0 ] && echo "layers: all rules hold"
exit $bad
