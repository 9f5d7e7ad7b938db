#!/usr/bin/env bash
# Command-line contract of `plantscale export` (issue 10): a simulated pass
# exported to every format, each file accepted by gdalinfo/ogrinfo; bad input
# exits 2 (or 1 for I/O) with a message naming what and where, and a failed
# export leaves the previous files byte-identical.
set -uo pipefail
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"

"$plantscale" simulate --preset field --length-m 3 --seed 4 --every 100 --quiet --out "$work/sim" >/dev/null \
  || { echo "FAIL: simulate"; exit 1; }
out="$work/out"
expect 0 "EPSG:32630" -- "$plantscale" export "$work/sim" --out "$out" --origin 52.0,-0.4 --heading 30 --quiet
for f in map.tif map.gpkg plants.geojson plants.csv map.png map.psmap TASKDATA/TASKDATA.XML TASKDATA/GRD00001.BIN; do
  [[ -s "$out/$f" ]] || fail "missing $out/$f"
done
ls -A "$out" | grep -q partial && fail "staging folder left in $out"
gdalinfo "$out/map.tif" | grep -q 'ID\["EPSG",32630\]' || fail "gdalinfo: map.tif lacks EPSG:32630"
gdalinfo "$out/map.tif" | grep -q "Overviews:" || fail "gdalinfo: map.tif has no overviews"
gdalinfo "$out/map.tif" | grep -q "NoData Value=65535" || fail "gdalinfo: map.tif has no nodata"
gdalinfo "$out/map_northup.tif" | grep -q "^Origin = " || fail "gdalinfo: map_northup.tif is not north-up"
gdalinfo "$out/map_northup.tif" | grep -q 'ID\["EPSG",32630\]' || fail "gdalinfo: map_northup.tif lacks EPSG:32630"
gdalinfo "$out/map.png" >/dev/null || fail "gdalinfo rejects map.png"
for layer in plants rows treated_areas run_metadata; do
  ogrinfo -so "$out/map.gpkg" "$layer" | grep -q "Feature Count: [1-9]" || fail "ogrinfo: map.gpkg layer $layer empty or unreadable"
done
ogrinfo -al -so "$out/plants.geojson" | grep -q 'ID\["EPSG",4326\]' || fail "ogrinfo: plants.geojson not WGS84"
ogrinfo -al -so "$out/plants.csv" | grep -q "Feature Count: [1-9]" || fail "ogrinfo rejects plants.csv"
grep -q '<GRD A="' "$out/TASKDATA/TASKDATA.XML" || fail "TASKDATA.XML lacks a GRD"

# The native map re-exports with its stored anchor, alone and merged with the run.
expect 0 "EPSG:32630" -- "$plantscale" export "$out/map.psmap" --out "$work/again" --format gtiff,csv --quiet
expect 0 "plants" -- "$plantscale" export "$out/map.psmap" "$work/sim" --out "$work/merged" --format gpkg --quiet
expect 0 "wrote .*map.png" -- "$plantscale" export "$work/sim" --out "$work/png" --format png --quiet
expect 0 "wrote .*TASKDATA" -- "$plantscale" export "$work/sim" --out "$work/iso" --format isoxml --origin 52,-0.4 --isoxml-cell-m 0.1 --quiet
grep -q "C=\"0.00000089" "$work/iso/TASKDATA/TASKDATA.XML" || fail "10 cm ISOXML cells are not 0.0000009 deg north"

# Bad input: exit 2 naming the key; I/O failures exit 1 naming the path.
expect 2 "epsg: unknown EPSG code 999999" -- "$plantscale" export "$work/sim" --out "$work/bad" --origin 52,-0.4 --epsg 999999
expect 2 "latitude_deg: must be in \[-90, 90\] \(got 95\)" -- "$plantscale" export "$work/sim" --out "$work/bad" --origin 95,0
expect 2 "expected LAT,LON" -- "$plantscale" export "$work/sim" --out "$work/bad" --origin north
expect 2 "need an origin" -- "$plantscale" export "$work/sim" --out "$work/bad"
expect 2 "unknown format 'shp'" -- "$plantscale" export "$work/sim" --out "$work/bad" --origin 52,0 --format shp
expect 2 "absent: LOG_OR_MAP: no such file or folder" -- "$plantscale" export "$work/absent" --out "$work/bad" --origin 52,0
[[ -e "$work/bad" ]] && fail "a refused export created $work/bad"
head -c 2000 "$out/map.psmap" >"$work/short.psmap"
expect 2 "short.psmap: truncated" -- "$plantscale" export "$work/short.psmap" --out "$work/bad" --origin 52,0
echo "not a map" >"$work/plain"
expect 1 "plain/x: cannot create folder" -- "$plantscale" export "$work/sim" --out "$work/plain/x" --origin 52,0 --quiet

# A disk that fills (file size limit, SIGXFSZ ignored): exit 1, old files intact.
cp -r "$out" "$work/before"
expect 1 "write failed|GDAL" -- bash -c "trap '' XFSZ; ulimit -f 8; exec \"$plantscale\" export \"$work/sim\" --out \"$out\" --origin 52.5,-0.4 --quiet"
diff -r "$work/before" "$out" >/dev/null || fail "a failed export changed $out"

finish "export CLI"
