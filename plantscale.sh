#!/usr/bin/env bash
# plantscale.sh: the two README commands.
#   ./plantscale.sh demo [plantscale demo options]   build, then run the whole system on the simulator into out/demo/
#   ./plantscale.sh test                             build, then run every test under Xvfb
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
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth
)

ensure_packages() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]} == 0)); then return; fi
  echo "plantscale.sh: installing ${missing[*]}" >&2
  local sudo=""
  if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
}

build() {
  local werror="$1"
  # shellcheck disable=SC2086
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DPLANTSCALE_WERROR="$werror" ${PLANTSCALE_CMAKE_ARGS:-}
  cmake --build build --parallel "$(nproc)"
}

usage() {
  echo "usage: $0 demo [options for 'plantscale demo'] | test" >&2
  exit 2
}

command="${1:-}"
[[ -n "$command" ]] || usage
shift
case "$command" in
  demo)
    ensure_packages
    build OFF
    ./build/app/plantscale demo "$@"
    ;;
  test)
    ensure_packages
    build ON
    cd build
    # -noreset: an X server resets when its last client leaves, and a test
    # that connects during the reset aborts ("bad X server connection").
    xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" \
      ctest --output-on-failure --parallel "$(nproc)" --timeout 900
    ;;
  *) usage ;;
esac
