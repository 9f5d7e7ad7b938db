#!/usr/bin/env bash
# The evaluation library's layering (docs/design.md):
#   engine <- app/config <- evaluation <- app (commands)
# Fails, naming file and line, when
#  - engine/ includes an evaluation/ or app/config/ header;
#  - evaluation/ includes a ui/ header or an app/ header other than the
#    libraries below it (app/config/, app/vehicle/): a command's header
#    would make the library depend on the command line;
#  - app/config/ (its library sources, not its tests) includes an
#    evaluation/, ui/ or other app/ header;
#  - a CMakeLists.txt of evaluation/ links plantscale_app or plantscale_ui,
#    or the plantscale_config target links plantscale_evaluation or
#    plantscale_app (outside comments).
# usage: evaluation_layering_test.sh SOURCE_DIR
set -uo pipefail
src="$1"
[[ -d "$src/evaluation" ]] || { echo "FAIL: no evaluation/ under '$src'"; exit 1; }
cd "$src" || exit 1
failures=0
include='^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"](\.\./)*'
allowed='#[[:space:]]*include[[:space:]]*[<"](\.\./)*app/'  # + what may follow, on file:line: hits

fail() {
  echo "FAIL: $1"
  failures=$((failures + 1))
}

while IFS= read -r hit; do
  fail "$hit: engine/ includes a header of evaluation/ or app/config/"
done < <(grep -rnIE "${include}(evaluation|app/config)/" engine)

while IFS= read -r hit; do
  fail "$hit: evaluation/ includes a header of ui/ or of an app/ command"
done < <(grep -rnIE "${include}(ui|app)/" evaluation | grep -vE "${allowed}(config|vehicle)/")

while IFS= read -r hit; do
  fail "$hit: app/config/ includes a header above it"
done < <(find app/config -name '*.cc' ! -name '*_test.cc' -o -name '*.h' | sort |
         xargs grep -nIE "${include}(evaluation|ui|app)/" | grep -vE "${allowed}config/")

while IFS= read -r cmake; do
  while IFS= read -r hit; do
    fail "$cmake:$hit: evaluation/ links the commands or the ui"
  done < <(sed 's/#.*//' "$cmake" | grep -nE '(^|[^[:alnum:]_])plantscale_(app|ui)([^[:alnum:]_]|$)')
done < <(find evaluation -name CMakeLists.txt | sort)

# The plantscale_config target's own link line (its test binary may link more).
while IFS= read -r hit; do
  fail "app/config/CMakeLists.txt: plantscale_config links $hit"
done < <(sed 's/#.*//' app/config/CMakeLists.txt |
         awk '/target_link_libraries\(plantscale_config/ {on = 1} on {print} on && /\)/ {on = 0}' |
         grep -oE 'plantscale_(evaluation|app|ui)([^[:alnum:]_]|$)')

if [[ $failures -ne 0 ]]; then
  echo "evaluation layering: $failures violation(s)"
  exit 1
fi
echo "evaluation layering: ok"
