# The helpers every CLI contract script shares: `source "$(dirname "$0")/cli_lib.sh"`
# at the top, `finish NAME` at the end.

failures=0

# fail MESSAGE: counts a failure and goes on (finish reports them all).
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# expect CODE PATTERN -- command...: exit code CODE and output matching PATTERN.
expect() {
  local code="$1" pattern="$2"
  shift 3
  local output status
  output=$("$@" 2>&1)
  status=$?
  if [[ $status -ne $code ]]; then
    fail "'$*' exited $status, expected $code"; echo "$output" | tail -5; return 0
  fi
  if ! grep -qE -- "$pattern" <<<"$output"; then
    fail "'$*' output lacks /$pattern/"; echo "$output" | tail -5; return 0
  fi
  echo "ok: $* -> $status"
}

# num KEY FILE: the first number given for "KEY" in a JSON file.
num() { grep -m1 -oE "\"$1\": [0-9.e+-]+" "$2" | awk '{print $2}'; }

# finish NAME: one line of summary; exit 1 when anything failed.
finish() {
  if ((failures)); then
    echo "$1: $failures failure(s)"
    exit 1
  fi
  echo "$1: ok"
  exit 0
}

# make_bad_certificates DIR: two certificates a client must refuse, with
# their keys, made with the openssl command line:
#   DIR/expired_cert.pem   valid 2020-01-01 to 2020-01-02 only (IP:127.0.0.1);
#   DIR/elsewhere_cert.pem for DNS:vehicle.farm.example only, not 127.0.0.1.
# (openssl req takes no start date in the past: `openssl ca -selfsign` does.)
make_bad_certificates() {
  local dir="$1"
  mkdir -p "$dir/ca" && : >"$dir/ca/index.txt" && echo 01 >"$dir/ca/serial"
  cat >"$dir/ca.cnf" <<CNF
[ca]
default_ca = d
[d]
database = $dir/ca/index.txt
new_certs_dir = $dir/ca
serial = $dir/ca/serial
default_md = sha256
policy = p
[p]
commonName = supplied
[ext]
subjectAltName = IP:127.0.0.1
basicConstraints = critical,CA:TRUE
CNF
  openssl req -new -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -subj /CN=127.0.0.1 \
    -keyout "$dir/expired_key.pem" -out "$dir/expired.csr" >/dev/null 2>&1 \
    && openssl ca -batch -config "$dir/ca.cnf" -selfsign -keyfile "$dir/expired_key.pem" -in "$dir/expired.csr" \
      -startdate 20200101000000Z -enddate 20200102000000Z -extensions ext -out "$dir/expired_cert.pem" \
      >"$dir/ca.txt" 2>&1 || { cat "$dir/ca.txt"; fail "openssl ca: the expired certificate"; }
  openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=vehicle \
    -addext "subjectAltName=DNS:vehicle.farm.example" -keyout "$dir/elsewhere_key.pem" \
    -out "$dir/elsewhere_cert.pem" >/dev/null 2>&1 || fail "openssl req: the wrong-name certificate"
}

# reconnected_within LOG BACK LIMIT: the station's first "connected to" line
# in LOG after unix time BACK (the link's return) comes within LIMIT s.
reconnected_within() {
  local log="$1" back="$2" limit="$3" again delay
  again=$(awk -v back="$back" '/station: gateway: .* connected to/ && $3 > back {print $3; exit}' "$log")
  if [[ -z "$again" ]]; then
    fail "the station ($log) did not reconnect after the link came back"
    return 0
  fi
  delay=$(awk -v a="$again" -v b="$back" 'BEGIN {printf "%.2f", a - b}')
  echo "reconnected ${delay} s after the link came back"
  awk -v d="$delay" -v l="$limit" 'BEGIN {exit !(d >= 0 && d <= l)}' ||
    fail "reconnected ${delay} s after the link came back (> ${limit} s)"
}

# station_tiles LOG: "N map tiles (R" from the station's model line.
station_tiles() { grep -oE "station: model: .* map tiles \([0-9]+ revisions\)" "$1" | grep -oE "[0-9]+ map tiles \([0-9]+"; }
