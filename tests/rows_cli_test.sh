#!/usr/bin/env bash
# plantscale detect-rows / evaluate rows (issue 11): outputs and their
# contract (CSV header row,v,u; JSON vanishing point, spacing, confidence),
# a folder with progress, no-row images (bare soil, sky), bad input.
# usage: rows_cli_test.sh PLANTSCALE WORKDIR
set -euo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
bin="$1"; work="$2"
rm -rf "$work"; mkdir -p "$work/in" "$work/empty"
# A dependency-free RGB PNG writer for the Python snippets below.
cat > "$work/pngw.py" <<'PY'
import struct, zlib
def png(path, w, h, pixel, depth=8):
    pack = (lambda p: bytes(p)) if depth == 8 else (lambda p: struct.pack(">HHH", *(257 * c for c in p)))
    raw = b"".join(b"\0" + b"".join(pack(pixel(x, y)) for x in range(w)) for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
PY

# Photographs made by the simulator (a clone has no photographs): a low,
# perspective view of preset C (horizon in view) and a colour view.
cat > "$work/low.yaml" <<YAML
camera: thesis
camera_overrides: {tilt_deg: 12, virtual_plane_height_m: 0.1}
field: {crop_radius_m: 0.12, weed_density_per_m2: 4.0}
length_m: 2
YAML
"$bin" simulate --preset "$work/low.yaml" --length-m 2 --every 10 --out "$work/sim" --quiet >/dev/null
cp "$work/sim/frames/000000.png" "$work/in/low.png"
"$bin" simulate --preset sanchiz_pla --length-m 2 --every 10 --out "$work/simrgb" --quiet >/dev/null
cp "$work/simrgb/frames/000000.png" "$work/in/colour.png"

# No rows: bare soil (brown noise) and a clear sky, written as PNG by Python.
python3 - "$work/in" "$work" <<'PY'
import random, sys
sys.path.insert(0, sys.argv[-1]); from pngw import png
random.seed(3)
def soil(x, y):
    g = random.randint(-25, 25)
    return (max(0, min(255, 120 + g)), max(0, min(255, 90 + g)), max(0, min(255, 65 + g)))
png(sys.argv[1] + "/soil.png", 320, 240, soil)
png(sys.argv[1] + "/sky.png", 200, 150, lambda x, y: (110 + y // 3, 160 + y // 4, 235))
# A tiny image and a 16-bit colour PNG of green stripes (issue 34): "no rows"
# or rows, never a crash.
png(sys.argv[1] + "/tiny.png", 16, 16, lambda x, y: (60, 150, 50) if x % 5 == 0 else (120, 90, 65))
png(sys.argv[1] + "/deep.png", 160, 120, lambda x, y: (60, 150, 50) if (x // 8) % 4 == 0 else (120, 90, 65), 16)
PY
echo "notes" > "$work/in/readme.txt"  # not an image: left out of the folder's images

# Bad input: empty, truncated, not an image, a missing file, an empty folder.
: > "$work/in/zero.jpg"
head -c 3000 "$work/in/low.png" > "$work/in/truncated.png"
printf '\xff\xd8\xff\xe0\x00\x10JFIF\x00\x01\x01\x00' > "$work/in/cut.jpg"  # a JPEG cut short
echo "not an image" > "$work/in/text.png"

set +e
"$bin" detect-rows "$work/in" "$work/empty" "$work/missing.png" --out "$work/out" \
  >"$work/stdout" 2>"$work/stderr"
rc=$?
set -e
[[ $rc -eq 0 ]] || fail "exit code $rc with bad images among good ones, want 0"
for f in zero.jpg truncated.png text.png missing.png cut.jpg; do
  grep -q "$f" "$work/stderr" || fail "no error naming $f"
done
grep -q "empty: no PNG or JPEG images" "$work/stderr" || fail "no error for the empty folder"
grep -q "detect-rows.*100%" "$work/stderr" || fail "no progress on standard error"
grep -q "6 image(s)" "$work/stdout" || fail "the batch did not go on past the bad files"
grep -q "readme.txt" "$work/stderr" && fail "a text file in a folder is not an image error"
for n in low colour soil sky tiny deep; do
  for ext in csv png json; do
    [[ -s "$work/out/${n}_rows.$ext" ]] || fail "missing ${n}_rows.$ext"
  done
  head -1 "$work/out/${n}_rows.csv" | grep -q "^row,v,u$" || fail "$n: CSV header"
  for key in vanishing_point spacing_bottom_px confidence; do
    grep -q "\"$key\"" "$work/out/${n}_rows.json" || fail "$n: JSON key $key missing"
  done
done
ls "$work/out" | grep -q partial && fail "staging files left behind"

# The perspective frame: three rows (the simulated bed), a vanishing point
# above the rows, rows from the bottom image row up, u measured in pixels.
python3 - "$work/out" <<'PY'
import csv, json, sys
out = sys.argv[1]
j = json.load(open(out + "/low_rows.json"))
assert j["confidence"] > 0.2, j
assert j["row_count"] == 3, j
assert j["vanishing_point"] is not None and j["vanishing_point"]["v"] < 200, j
assert 60 < j["spacing_bottom_px"] < 200, j
rows = list(csv.DictReader(open(out + "/low_rows.csv")))
assert {r["row"] for r in rows} == {"0", "1", "2"}, "rows numbered 0..2"
assert rows[0]["v"] == "479", "the CSV starts at the bottom image row"
bottom = [float(r["u"]) for r in rows if r["v"] == "479"]
assert bottom == sorted(bottom), "rows left to right"
assert abs(bottom[1] - 320) < 80, bottom
top = min(int(r["v"]) for r in rows)
assert top < 300, top
# No rows: confidence 0, no rows, an empty CSV (header only).
for n in ("soil", "sky"):
    j = json.load(open(out + "/" + n + "_rows.json"))
    assert j["confidence"] == 0 and j["row_count"] == 0 and j["rows"] == [], (n, j)
    assert j["vanishing_point"] is None and "reason" in j, (n, j)
    assert open(out + "/" + n + "_rows.csv").read() == "row,v,u\n", n
print("rows outputs: ok")
PY

# Only bad files: exit 2.
set +e
"$bin" detect-rows "$work/in/zero.jpg" "$work/in/truncated.png" "$work/empty" --out "$work/out3" \
  --quiet >/dev/null 2>"$work/stderr3"
rc=$?
set -e
[[ $rc -eq 2 ]] || fail "exit code $rc when no file could be processed, want 2"
grep -q "truncated.png" "$work/stderr3" || fail "no error naming truncated.png"

# Only good images: exit 0.
"$bin" detect-rows "$work/in/low.png" --out "$work/out2" --quiet >/dev/null \
  || fail "exit code on a good image"

# evaluate rows --json: the contract's key, and a real score.
"$bin" evaluate rows --preset C --seeds 1 --frames 3 --json > "$work/eval.json"
python3 - "$work/eval.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
for key in ("preset", "crda_mean", "frames", "image_rows_scored"):
    assert key in j, key
assert j["frames"] == 3 and j["image_rows_scored"] > 300, j
assert j["crda_mean"] >= 0.85, j
PY
# Labelled photographs (--images/--labels): five rows converging on a
# vanishing point above the image, and a label at half size with a white
# line along each row's centre, as the real datasets draw them. A second
# photograph has no label: an error naming it, and the score goes on.
mkdir -p "$work/photos" "$work/labels"
python3 - "$work/photos" "$work/labels" "$work" <<'PY'
import random, sys
sys.path.insert(0, sys.argv[-1]); from pngw import png
random.seed(5)
W, H, VP = 320, 240, -60.0
def centre(n, v):  # u of row n at continuous image height v
    return 160.0 + n * 70.0 * (v - VP) / (H - VP)
def photo(x, y):
    v, u = y + 0.5, x + 0.5
    half = 9.0 * (v - VP) / (H - VP)
    g = random.randint(-20, 20)
    if any(abs(u - centre(n, v)) < half for n in range(-2, 3)):
        return (max(0, 60 + g), min(255, 150 + g), max(0, 50 + g))
    return (max(0, 125 + g), max(0, 95 + g), max(0, 70 + g))
png(sys.argv[1] + "/rows.png", W, H, photo)
png(sys.argv[1] + "/unlabelled.png", W, H, photo)
def label(x, y):
    v = 2 * y + 1.0
    on = any(int(centre(n, v) / 2) == x for n in range(-2, 3))
    return (255, 255, 255) if on else (0, 0, 0)
png(sys.argv[2] + "/rows.png", W // 2, H // 2, label)
PY
"$bin" evaluate rows --images "$work/photos" --labels "$work/labels" --json \
  > "$work/photos.json" 2>"$work/stderr5" || true
grep -q "unlabelled.png: no label image" "$work/stderr5" || fail "no error naming the unlabelled photograph"
python3 - "$work/photos.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["images"] == 1 and j["images_with_rows"] == 1, j
assert len(j["per_image"]) == 1 and j["per_image"][0]["image"] == "rows.png", j
p = j["per_image"][0]
assert p["rows_found"] and p["image_rows_scored"] > 100, p
# Rows drawn exactly where the label says: CRDA near 1 (0.1 d tolerance).
assert p["crda"] > 0.8 and abs(p["crda"] - j["crda_mean"]) < 1e-9, j
PY

set +e
"$bin" evaluate rows --preset no_such_preset --json >/dev/null 2>"$work/stderr4"
rc=$?
set -e
[[ $rc -ne 0 ]] && grep -qi "no_such_preset" "$work/stderr4" || fail "unknown preset must fail clearly"
finish "rows CLI"
