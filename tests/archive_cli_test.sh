#!/usr/bin/env bash
# Command-line contract of the season archive (issue 37, docs/cli/archive.md)
# on a real PostgreSQL + PostGIS server (tests/pg_server.sh; exit 77 = skip
# when it cannot start) and on a GeoPackage: runs of one field exported
# (--to), re-exported (replaced, not duplicated), matched across runs,
# queried (text and JSON), one plant's history, the season as a GeoPackage;
# bad input (password, no PostGIS, refused connection, a log of no plants, a
# field name with SQL) and two exports at once; an export killed half-way
# leaves the whole run or none.
set -uo pipefail
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
here="$(cd "$(dirname "$0")" && pwd)"

# Under /tmp: the server runs as an unprivileged user when we are root, and
# the build folder may not be open to it.
pgdir=$(mktemp -u "${TMPDIR:-/tmp}/plantscale_pg.XXXXXX")
url=$(bash "$here/pg_server.sh" start "$pgdir") || { echo "skip: no PostgreSQL server"; exit 77; }
trap 'bash "$here/pg_server.sh" stop "$pgdir"' EXIT
port=$(cat "$pgdir/port")
sql() { PGPASSWORD=plantscale psql -X -qtA -h 127.0.0.1 -p "$port" -U plantscale -d archive -c "$1"; }

# Two runs of one bed (seeds differ: the same field is not simulated twice,
# so the runs share no plants; a map re-export of run 1 is the second visit).
"$plantscale" simulate --preset field --length-m 6 --seed 11 --publish --fast --lcm-url memq:// \
  --log "$work/run1.lcmlog" >/dev/null 2>&1 || fail "simulate run 1"
"$plantscale" simulate --preset field --length-m 6 --seed 13 --publish --fast --lcm-url memq:// \
  --log "$work/run3.lcmlog" >/dev/null 2>&1 || fail "simulate run 3"
"$plantscale" export "$work/run1.lcmlog" --out "$work/files" --format map --origin 52,-0.4 --heading 30 --quiet >/dev/null ||
  fail "export run 1 to a map"

expect 0 "run [0-9a-f]{16} of field 'north' bed 4 added: [1-9][0-9]* plants \(0 matched" -- \
  "$plantscale" export "$work/run1.lcmlog" --to "$url" --field north --bed 4 --origin 52,-0.4 --heading 30 --quiet
plants1=$(sql "SELECT COUNT(*) FROM plants")
expect 0 "replaced: $plants1 plants \($plants1 matched" -- \
  "$plantscale" export "$work/run1.lcmlog" --to "$url" --field north --bed 4 --quiet
[[ $(sql "SELECT COUNT(*) FROM runs") == 1 ]] || fail "a re-export duplicated the run"
[[ $(sql "SELECT COUNT(*) FROM plants") == "$plants1" ]] || fail "a re-export duplicated plants"
# The same plants from the map file (a second run id): every plant matched, no new season plant.
seasons=$(sql "SELECT COUNT(*) FROM season_plants")
expect 0 "added: $plants1 plants \($plants1 matched.* 0 new" -- \
  "$plantscale" export "$work/files/map.psmap" --to "$url" --field north --bed 4 --quiet
[[ $(sql "SELECT COUNT(*) FROM season_plants") == "$seasons" ]] || fail "matched plants got new season ids"
[[ $(sql "SELECT COUNT(*) FROM map_tiles") -ge 2 ]] || fail "no map tiles"
[[ $(sql "SELECT COUNT(*) FROM rows WHERE ST_Length(geom::geography) > 4") -ge 1 ]] || fail "no row of 4 m or more"
[[ $(sql "SELECT ST_SRID(geom) FROM plants LIMIT 1") == 4326 ]] || fail "plants are not WGS84"

expect 0 "field 'north': 2 run\(s\)" -- "$plantscale" archive query --to "$url" --field north
"$plantscale" archive query --to "$url" --field north --json >"$work/q.json" || fail "query --json"
for key in '"runs"' '"beds"' '"plants_per_m"' '"gaps"' '"median_size_m"' '"weeds_per_m2"' '"area_treated_m2"'; do
  grep -q "$key" "$work/q.json" || fail "query JSON lacks $key"
done
today=$(date -u +%F)
expect 0 "1 run\(s\)" -- "$plantscale" archive query --to "$url" --field north --from "$today" --to "$today"
expect 0 "0 run\(s\)" -- "$plantscale" archive query --to "$url" --field north --to 2000-01-01
id=$(sql "SELECT MIN(season_id) FROM plants")
expect 0 "plant $id of field 'north'.*seen in 2 run\(s\)" -- "$plantscale" archive plant "$id" --to "$url"
expect 2 "no plant 99999999" -- "$plantscale" archive plant 99999999 --to "$url"
expect 0 "wrote .*north.gpkg" -- "$plantscale" archive export --to "$url" --field north --out "$work/season"
ogrinfo -so "$work/season/north.gpkg" runs | grep -q "Feature Count: 2" || fail "season GeoPackage lacks its 2 runs"

# Field names are data: quotes and SQL stored and queried as written.
evil="O'Brien's'; DROP TABLE runs; --"
expect 0 "of field 'O'Brien's'; DROP TABLE runs; --'" -- \
  "$plantscale" export "$work/run3.lcmlog" --to "$url" --field "$evil" --origin 52,-0.4 --quiet
expect 0 "1 run\(s\)" -- "$plantscale" archive query --to "$url" --field "$evil"
[[ $(sql "SELECT COUNT(*) FROM runs") == 3 ]] || fail "the runs table lost runs"

# Bad input: exit 1 naming the server (password hidden) or exit 2 naming the option.
bad_pw="${url/plantscale:plantscale@/plantscale:wrongpw@}"
expect 1 "password authentication failed" -- "$plantscale" export "$work/run1.lcmlog" --to "$bad_pw" --field x --origin 52,0 --quiet
"$plantscale" export "$work/run1.lcmlog" --to "$bad_pw" --field x --origin 52,0 --quiet 2>&1 | grep -q wrongpw &&
  fail "the password is printed"
expect 1 "no PostGIS" -- "$plantscale" export "$work/run1.lcmlog" --to "${url%/archive}/plain" --field x --origin 52,0 --quiet
expect 1 "cannot connect" -- "$plantscale" export "$work/run1.lcmlog" --to "postgresql://u:p@127.0.0.1:1/db" --field x --origin 52,0 --quiet
expect 2 "is new to the archive: give its origin" -- "$plantscale" export "$work/run1.lcmlog" --to "$url" --field new --quiet
expect 2 "--field" -- "$plantscale" export "$work/run1.lcmlog" --to "$url" --origin 52,0 --quiet
# A log of no plants and no map tiles (one event, written by hand): exit 2, nothing stored.
python3 - "$work/empty.lcmlog" <<'PY'
import struct, sys
ch, data = b"PLANTSCALE_HEALTH", b"\0" * 16
with open(sys.argv[1], "wb") as f:
    f.write(struct.pack(">IqqII", 0xEDA1DA01, 0, 1700000000000000, len(ch), len(data)) + ch + data)
PY
expect 2 "no plants" -- "$plantscale" export "$work/empty.lcmlog" --to "$url" --field empty --origin 52,0 --quiet
[[ $(sql "SELECT COUNT(*) FROM runs WHERE field = 'empty'") == 0 ]] || fail "a run of no plants was stored"

# Two exports of the same plants into one new field at once (the log and its
# map file): both runs, every plant once in the season.
"$plantscale" export "$work/run1.lcmlog" --to "$url" --field south --origin 52,-0.4 --heading 30 --quiet >"$work/a.txt" 2>&1 &
a=$!
"$plantscale" export "$work/files/map.psmap" --to "$url" --field south --origin 52,-0.4 --heading 30 --quiet >"$work/b.txt" 2>&1 &
b=$!
wait $a || fail "concurrent export a: $(cat "$work/a.txt")"
wait $b || fail "concurrent export b: $(cat "$work/b.txt")"
[[ $(sql "SELECT COUNT(*) FROM runs WHERE field = 'south'") == 2 ]] || fail "a concurrent export lost a run"
[[ $(sql "SELECT COUNT(*) FROM plants WHERE field = 'south'") == $((2 * plants1)) ]] || fail "concurrent exports lost plants"
[[ $(sql "SELECT COUNT(*) FROM season_plants WHERE field = 'south'") == "$plants1" ]] ||
  fail "concurrent exports duplicated season plants: $(sql "SELECT COUNT(*) FROM season_plants WHERE field = 'south'") for $plants1"

# Killed half-way (SIGKILL at several moments): the run whole or absent.
for delay in 0.2 0.5 1.0; do
  "$plantscale" export "$work/run3.lcmlog" --to "$url" --field killed --origin 52,-0.4 --quiet >/dev/null 2>&1 &
  pid=$!
  sleep "$delay"
  kill -9 "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  n_runs=$(sql "SELECT COUNT(*) FROM runs WHERE field = 'killed'")
  n_plants=$(sql "SELECT COUNT(*) FROM plants WHERE field = 'killed'")
  want=$(sql "SELECT COALESCE(SUM(plants), 0) FROM runs WHERE field = 'killed'")
  [[ $n_plants == "$want" && $n_runs -le 1 ]] || fail "killed after ${delay}s: $n_runs runs, $n_plants plants (want $want)"
  echo "ok: killed after ${delay}s: $n_runs run(s), $n_plants plants"
done

# The GeoPackage archive: same schema, appended in place.
gpkg="$work/season.gpkg"
expect 0 "added" -- "$plantscale" export "$work/run1.lcmlog" --to "$gpkg" --field north --bed 4 --origin 52,-0.4 --heading 30 --quiet
expect 0 "added: $plants1 plants \($plants1 matched.* 0 new" -- "$plantscale" export "$work/files/map.psmap" --to "$gpkg" --field north --quiet
for layer in fields runs season_plants plants rows treated_areas map_tiles; do
  ogrinfo -so "$gpkg" "$layer" | grep -q "Feature Count: [1-9]" || fail "ogrinfo: $gpkg layer $layer empty or unreadable"
done
expect 0 "field 'north': 2 run\(s\)" -- "$plantscale" archive query --to "$gpkg" --field north
# Two exports of the same plants into the GeoPackage at once (it is locked per append).
"$plantscale" export "$work/run1.lcmlog" --to "$gpkg" --field west --origin 52,-0.4 --heading 30 --quiet >/dev/null &
a=$!
"$plantscale" export "$work/files/map.psmap" --to "$gpkg" --field west --origin 52,-0.4 --heading 30 --quiet >/dev/null &
b=$!
wait $a || fail "concurrent GeoPackage export a"
wait $b || fail "concurrent GeoPackage export b"
gcount() { ogrinfo -q -sql "$1" "$gpkg" | grep -oE "= [0-9]+" | grep -oE "[0-9]+"; }
[[ $(gcount "SELECT COUNT(*) FROM runs WHERE field = 'west'") == 2 ]] || fail "GeoPackage: a concurrent export lost a run"
[[ $(gcount "SELECT COUNT(*) FROM season_plants WHERE field = 'west'") == "$plants1" ]] ||
  fail "GeoPackage: concurrent exports duplicated season plants"

finish "archive CLI"
