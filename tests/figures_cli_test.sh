#!/usr/bin/env bash
# plantscale figures (issue 59): a small manifest run for real (a short
# test-bed run on one seed below 1000), figures.json and the document's
# marked places written, the same bytes again from a fresh work folder
# (except the date), resumed from the kept outputs, --check on a stale
# document, and bad manifests refused before anything runs.
# usage: figures_cli_test.sh PLANTSCALE WORKDIR SOURCE_DIR
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
bin="$1"; work="$2"; src="$3"
rm -rf "$work"; mkdir -p "$work/repo/docs/results"
repo="$work/repo"; manifest="$repo/docs/results/figures.yaml"

write_manifest() {  # write_manifest EXTRA_RUN_LINES
  cat >"$manifest" <<YAML
report_seeds: {first: 700, count: 1}
documents: [README.md]
runs:
  - name: bed
    command: evaluate tracking --preset testbed --length-m 4 --baseline thesis
$1
figures:
  - {name: bed.lateral, run: bed, key: lateral_rmse_m, unit: mm, digits: 2, target: "<= 5"}
  - {name: bed.thesis, run: bed, key: baseline_thesis.lateral_rmse_m, unit: mm, digits: 1}
tables:
  - name: t
    header: ["", target, ours, "thesis's"]
    rows:
      - [lateral RMSE, target:bed.lateral, bed.lateral, bed.thesis]
YAML
}
write_manifest ""
cat >"$repo/README.md" <<'MD'
# A tiny project
<!-- figures: quoted -->
Ours: <!-- figure: bed.lateral -->old<!-- /figure -->.

<!-- figures-table: t -->
<!-- /figures-table -->
<!-- /figures: quoted -->
MD

expect 0 "wrote .*figures.json \(2 figures" -- "$bin" figures --manifest "$manifest" --work "$work/w1" --quiet
json="$repo/docs/results/figures.json"
[[ -f "$json" ]] || fail "no figures.json"
grep -q '"command": "plantscale evaluate tracking --preset testbed --length-m 4 --baseline thesis --seed 700 --seeds 1 --json"' "$json" \
  || fail "figures.json lacks the run's command"
# A real value: the test bed's grid to better than a centimetre.
value=$(grep -A8 '"bed.lateral"' "$json" | grep -m1 -oE '"value": [0-9.e+-]+' | awk '{print $2}')
awk -v v="$value" 'BEGIN { exit !(v > 0 && v < 10) }' || fail "bed.lateral $value mm not in (0, 10)"
grep -qE "Ours: <!-- figure: bed.lateral -->[0-9]+\.[0-9]{2} mm<!-- /figure -->" "$repo/README.md" \
  || fail "the inline figure was not rendered"
grep -qE "^\| lateral RMSE \| ≤ 5 mm \| [0-9]+\.[0-9]{2} mm \| [0-9]+\.[0-9] mm \|$" "$repo/README.md" \
  || fail "the table was not rendered"
expect 0 "agree with" -- "$bin" figures --manifest "$manifest" --check

# The same bytes from a fresh work folder (nothing kept), except the date.
cp "$json" "$work/first.json"
expect 0 "wrote" -- "$bin" figures --manifest "$manifest" --work "$work/w2" --quiet
diff <(grep -v '"date"' "$work/first.json") <(grep -v '"date"' "$json") >/dev/null \
  || fail "a second run changed figures.json"
# Resumed: the kept output is read, nothing runs.
expect 0 "bed: kept from an earlier run" -- "$bin" figures --manifest "$manifest" --work "$work/w2"

# A document edited by hand is caught.
sed -i 's|<!-- figure: bed.lateral -->[^<]*<!-- /figure -->|<!-- figure: bed.lateral -->0.01 mm<!-- /figure -->|' "$repo/README.md"
expect 1 "figure bed.lateral says '0.01 mm'" -- "$bin" figures --manifest "$manifest" --check
echo "Also 42 mm by hand." >>"$repo/README.md"
sed -i 's|<!-- /figures: quoted -->||; $ a <!-- /figures: quoted -->' "$repo/README.md"
expect 1 "'42 mm' is quoted outside every figure marker" -- "$bin" figures --manifest "$manifest" --check

# Bad manifests: refused before anything runs (no new work folder), exit 2.
write_manifest "  - name: weather
    command: evaluate weather --preset field"
expect 2 "run weather: command 'evaluate weather --preset field' is not an evaluation" -- \
  "$bin" figures --manifest "$manifest" --work "$work/w3"
[[ ! -e "$work/w3" ]] || fail "a bad manifest ran something"
write_manifest "  - name: moon
    command: evaluate tracking --preset moon"
expect 2 "run moon: unknown preset 'moon'" -- "$bin" figures --manifest "$manifest" --work "$work/w3"
write_manifest "  - name: own
    command: evaluate tracking --preset field --seed 3"
expect 2 "run own: names --seed or --seeds" -- "$bin" figures --manifest "$manifest" --work "$work/w3"
write_manifest ""
sed -i 's/key: lateral_rmse_m, unit: mm/key: lateral_rmse, unit: mm/' "$manifest"
expect 2 "figure bed.lateral: key 'lateral_rmse' is not in what evaluate tracking --json prints" -- \
  "$bin" figures --manifest "$manifest" --work "$work/w3"
[[ ! -e "$work/w3" ]] || fail "a bad manifest ran something"
expect 2 "names no figure" -- "$bin" figures --manifest "$src/docs/results/figures.yaml" --only nowhere --check

# The repository's own documents agree with its figures.json.
expect 0 "agree with" -- "$bin" figures --manifest "$src/docs/results/figures.yaml" --check

finish figures
