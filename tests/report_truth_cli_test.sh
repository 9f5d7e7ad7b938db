#!/usr/bin/env bash
# plantscale report's agronomic summary against the simulator's truth
# (issue 36) on the field preset: a 40 m run published and logged
# (simulate --publish --fast --log over memq://), then `report --json`; the
# report rebuilds the simulated field from the log's run_config event and
# counts the truth over the same stand and rows. Crop plants, missing plants
# (gaps), median leaf-tip radius and weeds per m² must each be within 5 % of
# the truth. Needs no display (the report starts xvfb-run itself when it can,
# and writes everything but the camera views without one).
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"

log="$work/run.lcmlog"
"$plantscale" simulate --preset field --length-m 40 --publish --fast --lcm-url memq:// --quiet \
  --log "$log" >"$work/simulate.txt" 2>&1 || fail "simulate exited $?"
"$plantscale" report "$log" --out "$work/report" --json >"$work/summary.json" || fail "report --json exited $?"
python3 - "$work/summary.json" <<'PY' || fail "summary against truth (see above)"
import json, sys
j = json.load(open(sys.argv[1]))
a, t = j["agronomy"], j["truth"]
if t is None:
    sys.exit("no truth in summary.json: " + "; ".join(j["problems"]))
checks = [
    ("crop plants", a["crop_plants"], t["crop_plants"]),
    ("missing plants", a["missing_plants"], t["missing_plants"]),
    ("median crop leaf-tip radius (m)", a["crop_radius"]["median_m"], t["median_radius_m"]),
    ("weeds per m2", a["weeds_per_m2"], t["weeds_per_m2"]),
]
bad = 0
for name, got, want in checks:
    rel = abs(got - want) / want if want else float("inf")
    print(f"{name}: report {got:.4g}, truth {want:.4g}, {100 * rel:.1f} % off (limit 5 %)")
    bad += rel > 0.05
sys.exit(1 if bad else 0)
PY
finish "report against simulator truth"
