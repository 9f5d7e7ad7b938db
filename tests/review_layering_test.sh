#!/usr/bin/env bash
# The review library and the archive and export code link no VTK
# (review/README.md, docs/design.md): plantscale_review (review/) and
# plantscale_export (app/: the season archive and `plantscale export`) sit
# below ui/, which alone uses VTK. Fails, naming file and line or the chain
# of targets, when
#  - a file under review/ includes a VTK header or one of ui/, app/ or
#    evaluation/;
#  - a source of a checked target (or the header beside it) includes a VTK
#    or ui/ header;
#  - a checked target links a VTK target (VTK::*) or plantscale_ui, directly
#    or through another target (the closure CMake wrote at configure time,
#    tests/CMakeLists.txt plantscale_link_closure);
#  - the test binary given, linked against the review library, needs a VTK
#    shared library (readelf -d).
# usage: review_layering_test.sh SOURCE_DIR CLOSURE_FILE [TEST_BINARY]
# CLOSURE_FILE lines: "source <target> <file>" and "link <target> <item> <chain>".
set -uo pipefail
src="$1"
closure="$2"
binary="${3:-}"
[[ -d "$src/review" ]] || { echo "FAIL: no review/ under '$src'"; exit 1; }
[[ -s "$closure" ]] || { echo "FAIL: no link closure in '$closure' (re-run cmake)"; exit 1; }
closure=$(realpath "$closure")
[[ -z "$binary" ]] || binary=$(realpath "$binary")
cd "$src" || exit 1
failures=0
include='^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"](\.\./)*'

fail() {
  echo "FAIL: $1"
  failures=$((failures + 1))
}

while IFS= read -r hit; do
  fail "$hit: review/ includes a VTK header or one of ui/, app/ or evaluation/"
done < <(grep -rnIE "${include}(vtk|ui/|app/|evaluation/)" review)

sources=0
while read -r kind target file; do
  [[ "$kind" == source ]] || continue
  sources=$((sources + 1))
  for f in "$file" "${file%.cc}.h"; do
    [[ -f "$f" ]] || continue
    while IFS= read -r hit; do
      fail "$f:$hit: $target (no VTK) includes a VTK or ui/ header"
    done < <(grep -nIE "${include}(vtk|ui/)" "$f")
  done
done < "$closure"
[[ $sources -gt 0 ]] || fail "$closure lists no sources"

links=0
while read -r kind target item chain; do
  [[ "$kind" == link ]] || continue
  links=$((links + 1))
  if [[ "$item" =~ VTK:: || "$item" =~ (^|/)libvtk || "$item" == plantscale_ui ]]; then
    fail "$target links $item ($chain)"
  fi
done < "$closure"
[[ $links -gt 0 ]] || fail "$closure lists no links"

if [[ -n "$binary" ]]; then
  if ! needed=$(readelf -d "$binary" 2>&1); then
    fail "readelf -d $binary: $needed"
  else
    while IFS= read -r lib; do
      fail "$binary needs $lib"
    done < <(grep -oE 'Shared library: \[libvtk[^]]*\]' <<< "$needed")
  fi
fi

if [[ $failures -ne 0 ]]; then
  echo "review layering: $failures violation(s)"
  exit 1
fi
echo "review layering: ok ($sources sources, $links linked items checked)"
