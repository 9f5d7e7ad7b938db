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
