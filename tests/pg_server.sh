#!/usr/bin/env bash
# A throw-away PostgreSQL + PostGIS server for the archive tests (issue 37):
# initdb and pg_ctl from Debian's postgresql packages, in a temporary folder,
# listening on 127.0.0.1 only at a free port, password (scram) login.
#
#   pg_server.sh start DIR   creates DIR (must not exist), starts the server and
#                            prints its URL on stdout:
#                              postgresql://plantscale:plantscale@127.0.0.1:PORT/archive
#                            Databases: `archive` (PostGIS installed) and
#                            `plain` (no PostGIS). Exit 77 and the reason on
#                            stderr when the server cannot start (no PostgreSQL,
#                            no PostGIS, no unprivileged user).
#   pg_server.sh stop DIR    stops the server and removes DIR.
#
# initdb refuses to run as root (CI runs as root), so as root the server
# runs as the `postgres` user (else `nobody`) in a folder that user owns.
set -uo pipefail

cmd="${1:-}"
dir="${2:-}"
[[ -n "$cmd" && -n "$dir" ]] || { echo "usage: pg_server.sh start|stop DIR" >&2; exit 2; }

pg_bin() {
  local b
  for b in /usr/lib/postgresql/*/bin; do [[ -x "$b/initdb" ]] && { echo "$b"; return 0; }; done
  return 1
}

skip() { echo "pg_server.sh: cannot start PostgreSQL: $*" >&2; exit 77; }

# as_user CMD...: runs CMD as the server's user (itself when not root).
as_user() {
  if [[ $(id -u) -ne 0 ]]; then "$@"; return; fi
  local user
  user=$(cat "$dir/user")
  setpriv --reuid="$user" --regid="$(id -g "$user")" --clear-groups --reset-env -- "$@"
}

start() {
  local bin user port
  bin=$(pg_bin) || skip "no initdb under /usr/lib/postgresql/*/bin (apt-get install postgresql)"
  local share
  share=$("$bin/pg_config" --sharedir 2>/dev/null || echo /usr/share/postgresql/15)
  ls "$share"/extension/postgis.control >/dev/null 2>&1 ||
    skip "no PostGIS extension in $share/extension (apt-get install postgresql-15-postgis-3)"
  [[ ! -e "$dir" ]] || { echo "pg_server.sh: $dir exists" >&2; exit 2; }
  mkdir -p "$dir" || skip "cannot create $dir"
  if [[ $(id -u) -eq 0 ]]; then
    user=postgres
    id "$user" >/dev/null 2>&1 || user=nobody
    echo "$user" >"$dir/user"
    chown "$user" "$dir"
    # The user must reach DIR: every folder above it open to others.
    setpriv --reuid="$user" --regid="$(id -g "$user")" --clear-groups -- test -x "$dir" ||
      skip "$user cannot reach $dir (a folder above it is closed to others)"
  fi
  echo plantscale >"$dir/pwfile"
  [[ $(id -u) -ne 0 ]] || chown "$(cat "$dir/user")" "$dir/pwfile"
  as_user "$bin/initdb" -D "$dir/data" -U plantscale --pwfile="$dir/pwfile" --auth=scram-sha-256 \
    -E UTF8 --locale=C.UTF-8 >"$dir/initdb.log" 2>&1 || skip "initdb failed: $(tail -3 "$dir/initdb.log")"
  local tries
  for tries in 1 2 3 4 5 6 7 8; do
    port=$((20000 + (RANDOM * 32768 + RANDOM) % 40000))
    if as_user "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 30 \
         -o "-c listen_addresses=127.0.0.1 -p $port -k $dir -c fsync=off -c max_connections=50" \
         start >/dev/null 2>&1; then
      echo "$port" >"$dir/port"
      break
    fi
  done
  [[ -f "$dir/port" ]] || skip "pg_ctl start failed: $(tail -3 "$dir/server.log" 2>/dev/null)"
  export PGPASSWORD=plantscale
  local psql=("$bin/psql" -X -q -v ON_ERROR_STOP=1 -h 127.0.0.1 -p "$port" -U plantscale)
  "${psql[@]}" -d postgres -c "CREATE DATABASE archive" -c "CREATE DATABASE plain" >"$dir/setup.log" 2>&1 &&
    "${psql[@]}" -d archive -c "CREATE EXTENSION postgis" -c "CREATE EXTENSION postgis_raster" \
      >>"$dir/setup.log" 2>&1 || { stop; skip "PostGIS setup failed: $(tail -3 "$dir/setup.log")"; }
  echo "postgresql://plantscale:plantscale@127.0.0.1:$port/archive"
}

stop() {
  local bin
  bin=$(pg_bin) || return 0
  [[ -d "$dir/data" ]] && as_user "$bin/pg_ctl" -D "$dir/data" -m immediate -w stop >/dev/null 2>&1
  rm -rf "$dir"
}

case "$cmd" in
  start) start ;;
  stop) stop ;;
  *) echo "usage: pg_server.sh start|stop DIR" >&2; exit 2 ;;
esac
