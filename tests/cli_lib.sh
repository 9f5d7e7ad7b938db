# Shared helpers of the CLI contract scripts: `source tests/cli_lib.sh` after
# setting `failures=0`.

fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

expect() {  # expect CODE PATTERN -- command...: exit code CODE and output matching PATTERN
  local code="$1" pattern="$2"
  shift 3
  local output status
  output=$("$@" 2>&1)
  status=$?
  if [[ $status -ne $code ]]; then
    fail "'$*' exited $status, expected $code"; echo "$output" | tail -5; return
  fi
  if ! grep -qE -- "$pattern" <<<"$output"; then
    fail "'$*' output lacks /$pattern/"; echo "$output" | tail -5; return
  fi
  echo "ok: $* -> $status"
}
