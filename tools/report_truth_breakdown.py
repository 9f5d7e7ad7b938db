#!/usr/bin/env python3
"""report_truth_breakdown: the weeds of a `plantscale report` against the
simulator's truth, weed by weed (a development aid for issue 36; the
figures in docs/results come from `report --json`).

Inputs: the truth of the same run (`plantscale simulate --preset P --seed S
--length-m L --out DIR --every 100000` writes DIR/truth/plants.csv), the
report's summary.json (stand, rows, row spacing and the bed frame's
registration on the field, from its truth source), and the plant records,
the log's published plants (`--plants`: plants.csv of `plantscale export
LOG --format csv --origin 52,0`), and optionally the records that never
were published (`--records`: a CSV of the registry's records with columns
id,x,y,crop, e.g. a debugging dump), as unconfirmed.

Each true weed in the band (the report's rows ± half a row spacing, its
stand along them) is: matched (a confirmed weed record within max(5 cm,
its radius)); else wholly under a crop canopy (its disc inside 0.75 of the
crop's leaf-tip radius), against a crop canopy (its disc overlapping the
leaf-tip disc) or clear; and of the unmatched, how many have an
unconfirmed weed record near. Weed records with no true weed within
max(5 cm, ...) are counted as false, split by whether they stand on a
crop's canopy.

The bed frame is registered on the field by one shift along the row, but
the grid's plant spacing drifts against the field's over a run (crop
records ±4 cm off their crops on a 40 m run), which this matching would
count as lost weeds and false records. `--drift` takes it out: each record's
y is moved by the median offset of the crop records from their true crops
(nearest within 8 cm) in its 2 m of the run.
usage: report_truth_breakdown.py --truth DIR/truth/plants.csv --summary summary.json --plants plants.csv [--records dump.csv] [--drift]
"""
import argparse
import csv
import json
import math
import re
import sys


def load_truth(path):
    crops, weeds = [], []
    with open(path) as f:
        for r in csv.DictReader(f):
            p = (float(r["x_m"]), float(r["y_m"]), float(r["radius_m"]))
            (crops if r["class"] == "crop" else weeds).append(p)
    return crops, weeds


def load_records(path):
    out = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            out[int(r["id"])] = r  # the last state of each record
    return list(out.values())


def near(points, x, y, reach):
    return [p for p in points if abs(p[1] - y) <= reach and math.hypot(p[0] - x, p[1] - y) <= reach]


def drift_corrected(recs, crops, bin_m=2.0, reach_m=0.08):
    offsets = {}
    for x, y, c, k, r in recs:
        if not k:
            continue
        near_crops = near(crops, x, y, reach_m)
        if near_crops:
            cx, cy, _ = min(near_crops, key=lambda p: math.hypot(p[0] - x, p[1] - y))
            offsets.setdefault(math.floor(y / bin_m), []).append(y - cy)
    med = {b: sorted(v)[len(v) // 2] for b, v in offsets.items()}

    def shift(y):
        b = math.floor(y / bin_m)
        for d in (0, -1, 1, -2, 2):
            if b + d in med:
                return med[b + d]
        return 0.0
    return [(x, y - shift(y), c, k, r) for x, y, c, k, r in recs]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--truth", required=True)
    ap.add_argument("--summary", required=True)
    ap.add_argument("--plants", required=True)
    ap.add_argument("--records")
    ap.add_argument("--drift", action="store_true")
    a = ap.parse_args()
    j = json.load(open(a.summary))
    ag = j["agronomy"]
    m = re.search(r"at ([+-]\d+) rows, ([+-]?[\d.]+) m", j["truth"]["source"])
    dr, dy = int(m.group(1)), float(m.group(2))
    rs = ag["row_spacing_m"]
    rows = [r["row"] for r in ag["rows"]]
    x_lo, x_hi = (min(rows) - 0.5) * rs, (max(rows) + 0.5) * rs
    y0, y1 = ag["stand_y0_m"], ag["stand_y1_m"]
    crops, weeds = load_truth(a.truth)
    dx = dr * rs
    recs = []
    published = set()
    with open(a.plants) as f:
        for r in csv.DictReader(f):
            published.add(int(r["plant_id"]))
            recs.append((float(r["field_x_m"]) + dx, float(r["field_y_m"]) + dy, 1, int(r["class"] == "crop"), r))
    if a.drift:
        recs = drift_corrected(recs, crops)
    crop_r = sorted(float(r["radius_m"]) for x, y, c, k, r in recs if k)
    big = 0.55 * crop_r[len(crop_r) // 2] if crop_r else math.inf  # (1 - 3 * 0.15) of the crops' median radius
    for r in load_records(a.records) if a.records else []:
        if int(r["id"]) not in published:
            recs.append((float(r["x"]) + dx, float(r["y"]) + dy, 0, int(r["crop"]), r))
    band = [w for w in weeds if x_lo + dx <= w[0] <= x_hi + dx and y0 + dy <= w[1] <= y1 + dy]
    weed_recs = [(x, y, c, 0, r) for x, y, c, k, r in recs if not k]
    conf = [(x, y) for x, y, c, k, r in weed_recs if c]
    unconf = [(x, y, r) for x, y, c, k, r in weed_recs if not c]
    cat = {"matched": 0, "under": 0, "against": 0, "clear": 0}
    unmatched_with_unconfirmed = {"under": 0, "against": 0, "clear": 0}
    for wx, wy, wr in band:
        reach = max(0.05, wr)
        if any(math.hypot(x - wx, y - wy) <= reach for x, y in conf):
            cat["matched"] += 1
            continue
        kind = "clear"
        for cx, cy, cr in near(crops, wx, wy, 0.5):
            d = math.hypot(cx - wx, cy - wy)
            if d + wr <= 0.75 * cr:
                kind = "under"
                break
            if d - wr < cr:
                kind = "against"
        cat[kind] += 1
        if any(math.hypot(x - wx, y - wy) <= reach for x, y, _ in unconf):
            unmatched_with_unconfirmed[kind] += 1
    in_band = [(x, y, float(r["radius_m"])) for x, y, c, k, r in weed_recs
               if c and x_lo + dx <= x <= x_hi + dx and y0 + dy <= y <= y1 + dy]
    false_on_crop = false_clear = near_miss = crop_sized = 0
    for x, y, radius in in_band:
        if any(math.hypot(x - wx, y - wy) <= max(0.05, wr) for wx, wy, wr in near(weeds, x, y, 0.2)):
            continue
        if radius >= big:
            crop_sized += 1
            continue
        if near(weeds, x, y, 0.1):
            near_miss += 1
            continue
        on_crop = any(math.hypot(x - cx, y - cy) < cr for cx, cy, cr in near(crops, x, y, 0.5))
        false_on_crop += on_crop
        false_clear += not on_crop
    unconf_far = sum(1 for x, y, _ in unconf if x_lo + dx <= x <= x_hi + dx and y0 + dy <= y <= y1 + dy
                     and not any(math.hypot(x - wx, y - wy) <= max(0.05, wr) for wx, wy, wr in near(weeds, x, y, 0.2)))
    area = (x_hi - x_lo) * (y1 - y0)
    print(json.dumps({
        "true_weeds_in_band": len(band), **cat,
        "unmatched_with_unconfirmed_record": unmatched_with_unconfirmed,
        "confirmed_weed_records_in_band": len(in_band),
        "other_weed_records": {"crop_sized": crop_sized, "weed_5_10_cm_away": near_miss,
                               "on_crop": false_on_crop, "clear": false_clear},
        "unconfirmed_weed_records_near_no_weed": unconf_far,
        "truth_per_m2": len(band) / area, "visible_truth_per_m2": (len(band) - cat["under"]) / area,
        "records_per_m2": len(in_band) / area, "report_per_m2": ag["weeds_per_m2"],
    }, indent=1))


if __name__ == "__main__":
    sys.exit(main())
