#!/usr/bin/env bash
# The engine's layering: engine/ is the on-vehicle library (pure C++, no
# I/O) and must not depend on maps/, telemetry/, review/, ui/, app/ or
# evaluation/.
# Fails, naming file and line, on an #include of those folders in any file
# under engine/, or on a mention of their targets in an engine
# CMakeLists.txt (outside comments), which is how an engine target would
# link them.
# usage: layering_test.sh SOURCE_DIR
set -uo pipefail
src="$1"
[[ -d "$src/engine" ]] || { echo "FAIL: no engine/ under '$src'"; exit 1; }
cd "$src" || exit 1
failures=0

while IFS= read -r hit; do
  echo "FAIL: $hit: engine/ includes a header of maps/, telemetry/, review/, ui/, app/ or evaluation/"
  failures=$((failures + 1))
done < <(grep -rnIE '^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"](\.\./)*(maps|telemetry|review|ui|app|evaluation)/' engine)

while IFS= read -r cmake; do
  while IFS= read -r hit; do
    echo "FAIL: $cmake:$hit: an engine target links a non-engine library"
    failures=$((failures + 1))
  done < <(sed 's/#.*//' "$cmake" |
           grep -nE '(^|[^[:alnum:]_])plantscale_(maps|telemetry|can|review|ui|app|config|evaluation|export|command_registry)([^[:alnum:]_]|$)')
done < <(find engine -name CMakeLists.txt | sort)

if [[ $failures -ne 0 ]]; then
  echo "engine layering: $failures violation(s)"
  exit 1
fi
echo "engine layering: ok"
