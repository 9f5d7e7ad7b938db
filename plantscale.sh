#!/usr/bin/env bash
# plantscale.sh: the two README commands.
#   ./plantscale.sh demo [plantscale demo options]   build, then run the whole system on the simulator into out/demo/
#   ./plantscale.sh test                             build, then run every test under Xvfb
#   ./plantscale.sh test --fast                      build, then the unit tests only (ctest -L unit): the edit loop
#   ./plantscale.sh soak                             build, then the 5 km soak run (bounded memory, the last 100 m sprayed)
#   ./plantscale.sh fuzz [SECONDS]                   build the fuzz targets (clang), run each SECONDS
#   ./plantscale.sh sanitize                         the unit tests under ASan + UBSan only
#   ./plantscale.sh complexity [FILE...]             clang-tidy's function size and cognitive complexity
#                                                    checks (thresholds in .clang-tidy) on the product's sources
# With PLANTSCALE_SANITIZED=1, `test` also runs the unit tests under ASan +
# UBSan (build-asan/) and each fuzz target for 10 s (build-fuzz/).
# Each installs the Debian packages it needs when they are missing (apt is
# skipped entirely when they are all present) and builds with ccache into build/.
# Extra CMake arguments: PLANTSCALE_CMAKE_ARGS="-DPLANTSCALE_SANITIZE=address,undefined".
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config
  libeigen3-dev libopencv-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev libspdlog-dev
  liblcm-dev liblcm-bin libglib2.0-dev
  libgdal-dev gdal-bin
  libvtk9-dev
  libssl-dev
  libboost-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth
)
# tests/fuzz (docs/fuzzing.md): clang and its libFuzzer/ASan runtimes.
FUZZ_PACKAGES=(clang libclang-rt-dev)
# The full test suite also opens a report in headless Chromium (cli.report_browser).
# The archive tests (tests/pg_server.sh) start PostgreSQL with PostGIS.
# The learned segmenter's test trains a model (train-segmenter: Debian's
# PyTorch and ONNX for /usr/bin/python3; training only, never on the vehicle).
# The gateway's test (cli.gateway) runs npm's Foxglove client under Node.js over TLS.
TEST_PACKAGES=(chromium postgresql postgresql-15-postgis-3 python3-numpy python3-torch python3-onnx
  nodejs openssl)
# Debian's npm conflicts with a nodejs that bundles its own (NodeSource's, as
# these machines have): it is asked for only where no npm is found.
command -v npm >/dev/null 2>&1 || TEST_PACKAGES+=(npm)

ensure_packages() {
  local missing=()
  for p in "${PACKAGES[@]}" "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]} == 0)); then return; fi
  echo "plantscale.sh: installing ${missing[*]}" >&2
  local sudo=""
  if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
}

# demo and test configure build/ alike (warnings are errors in both), so one
# after the other recompiles nothing.
build() {
  # shellcheck disable=SC2086
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DPLANTSCALE_WERROR=ON ${PLANTSCALE_CMAKE_ARGS:-}
  cmake --build build --parallel "$(nproc)"
}

# Unit test binaries run again under ASan + UBSan (build-asan/, GCC): the
# engine's, telemetry's, maps', the vehicle's, app/config's and
# evaluation/'s (docs/fuzzing.md). Not ui_test and app_test (they link VTK;
# ui_test needs Xvfb), nor system_test, fault_test and the CLI scripts
# (minutes of simulation each, and the whole program).
SANITIZED_TESTS=(common_test geometry_test sim_test vision_test rows_test tracking_test motion_test
  classify_test treatment_test pipeline_test telemetry_test maps_test vehicle_test config_test
  evaluation_test)

run_sanitized_tests() {
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPLANTSCALE_WERROR=ON \
    -DPLANTSCALE_BUILD_BENCHMARKS=OFF -DPLANTSCALE_SANITIZE=address,undefined
  cmake --build build-asan --parallel "$(nproc)" --target "${SANITIZED_TESTS[@]}"
  local labels
  labels="^($(IFS='|'; echo "${SANITIZED_TESTS[*]}"))\$"
  (cd build-asan &&
    ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      ctest -L "$labels" --output-on-failure --parallel "$(nproc)" --timeout 900)
}

# The fuzz targets with clang, libFuzzer, ASan and UBSan in build-fuzz/
# (only the libraries they link are built).
build_fuzz() {
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DPLANTSCALE_FUZZ=ON
  cmake --build build-fuzz --target plantscale_fuzzers --parallel "$(nproc)"
}

# Runs every fuzz target for $1 seconds, $(nproc) at a time, on its seeds
# plus the inputs kept from earlier runs (build-fuzz/tests/fuzz/corpus/);
# prints executions and crashes per target and fails when any crashed.
run_fuzzers() {
  local seconds="$1" dir=build-fuzz/tests/fuzz logs=build-fuzz/tests/fuzz/logs
  mkdir -p "$logs" "$dir/artifacts"
  local targets=()
  for f in tests/fuzz/*_fuzz.cc; do targets+=("$(basename "$f" .cc)"); done
  local running=0
  for t in "${targets[@]}"; do
    mkdir -p "$dir/corpus/$t"
    ("$dir/$t" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$dir/artifacts/$t-" "$dir/corpus/$t" "tests/fuzz/corpus/$t" \
      >"$logs/$t.log" 2>&1
     echo $? >"$logs/$t.rc") &
    running=$((running + 1))
    if ((running >= $(nproc))); then wait -n || true; running=$((running - 1)); fi
  done
  wait || true
  local failed=0
  printf '%-16s %12s %10s %8s  %s\n' target executions exec/s crashes "corpus (kept)"
  for t in "${targets[@]}"; do
    local log="$logs/$t.log" execs rate crashes
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    [[ -n "$execs" ]] || execs=$(grep -o '^#[0-9]*' "$log" | tail -1 | tr -d '#')
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    crashes=$(grep -c -E 'Test unit written to .*/[a-z_]+-(crash|oom|timeout|leak)-' "$log" || true)
    printf '%-16s %12s %10s %8s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "$crashes" \
      "$(find "$dir/corpus/$t" -type f | wc -l)"
    if ((crashes > 0)) || [[ "$(cat "$logs/$t.rc")" != 0 ]]; then
      failed=1
      grep -E 'SUMMARY|Test unit written to' "$log" | sed 's/^/    /'
    fi
  done
  echo "logs: $logs/"
  return "$failed"
}

# The two checks that keep functions readable as their steps, on the given
# files or every product source (not tests, benchmarks or fuzz targets); the
# thresholds are in .clang-tidy. Fails when a function exceeds them. The
# compiler's own diagnostics are left out (clang 14 parses some of GCC 12's
# ranges headers with errors; the checks still see the file's functions).
run_complexity() {
  local files=("$@")
  if ((${#files[@]} == 0)); then
    mapfile -t files < <(find engine app maps telemetry review ui tools -name '*.cc' ! -name '*_test.cc' | sort)
  fi
  local checks='-*,readability-function-cognitive-complexity,readability-function-size' found
  found=$(printf '%s\n' "${files[@]}" | xargs -P "$(nproc)" -n 8 clang-tidy -p build --quiet \
    --checks="$checks" --extra-arg=-Wno-everything 2>/dev/null |
    grep -E '\[readability-function-(cognitive-complexity|size)\]' || true)
  if [[ -n "$found" ]]; then
    echo "$found"
    return 1
  fi
  echo "complexity: ${#files[@]} files, no function over the thresholds in .clang-tidy"
}

usage() {
  echo "usage: $0 demo [options for 'plantscale demo'] | test [--fast] | soak | fuzz [SECONDS] | sanitize | complexity [FILE...]" >&2
  exit 2
}

command="${1:-}"
[[ -n "$command" ]] || usage
shift
case "$command" in
  demo)
    ensure_packages
    build
    ./build/app/plantscale demo "$@"
    ;;
  test)
    if [[ "${1:-}" == --fast ]]; then ensure_packages; else ensure_packages "${TEST_PACKAGES[@]}"; fi
    build
    if [[ "${1:-}" == --fast ]]; then
      (cd build && ctest -L '^unit$' --output-on-failure --parallel "$(nproc)" --timeout 300)
      exit 0
    fi
    [[ $# -eq 0 ]] || usage
    # -noreset: an X server resets when its last client leaves, and a test
    # that connects during the reset aborts ("bad X server connection").
    # The 5 km soak (label soak, about 20 CPU minutes) runs with `soak`.
    (cd build && xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" \
      ctest -LE '^soak$' --output-on-failure --parallel "$(nproc)" --timeout 900)
    if [[ "${PLANTSCALE_SANITIZED:-0}" == 1 ]]; then
      ensure_packages "${FUZZ_PACKAGES[@]}"
      run_sanitized_tests
      build_fuzz
      (cd build-fuzz && ctest -L '^fuzz$' --output-on-failure --parallel "$(nproc)")
    fi
    ;;
  soak)
    ensure_packages
    build
    (cd build && ctest -L '^soak$' --output-on-failure --timeout 3600)
    ;;
  sanitize)
    ensure_packages
    run_sanitized_tests
    ;;
  complexity)
    ensure_packages clang-tidy
    build
    run_complexity "$@"
    ;;
  fuzz)
    seconds="${1:-60}"
    [[ "$seconds" =~ ^[0-9]+$ ]] || usage
    ensure_packages "${FUZZ_PACKAGES[@]}"
    build_fuzz
    run_fuzzers "$seconds"
    ;;
  *) usage ;;
esac
