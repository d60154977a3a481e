#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine (run as root):
#   bash tools/setup.sh demo   install dependencies, build, run `hil demo`
#   bash tools/setup.sh test   install dependencies (and the vcan VM), build, run every test
#   bash tools/setup.sh deps | vm | build
# Sanitizer runs (ASan+UBSan, TSan): tools/sanitize.sh.
# Everything comes from Debian's archive (apt-get); nothing else is downloaded.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HIL_BUILD_DIR:-$here/build}"
jobs="${HIL_JOBS:-$(nproc)}"

deps() {
  export DEBIAN_FRONTEND=noninteractive
  local pkgs=(
    build-essential cmake ninja-build pkg-config python3
    libeigen3-dev libspdlog-dev libfmt-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
    libmodbus-dev libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools default-jre-headless
    libtinyxml2-dev  # the Net F/T calibration page (drivers)
    libboost-dev  # Boost.Math's Student t quantiles (diagnosis/src/engine.cpp)
    can-utils iproute2 libgtest-dev libgmock-dev libbenchmark-dev zlib1g-dev libzstd-dev liblz4-dev
    python3-can python3-pymodbus python3-serial-asyncio python3-numpy python3-jsonschema
    pybind11-dev python3-dev python3-pytest
    openssl
    cyclonedds-dev cyclonedds-tools  # the second DDS vendor beside hil (tests/interop)
    liburdfdom-dev libkdl-parser-dev liborocos-kdl-dev  # URDF robots (formats/format/src/urdf.cpp)
    clang libclang-rt-14-dev lld  # libFuzzer targets (tests/fuzz)
    clang-format  # the tree's style, checked by tests/architecture/format (tools/format.sh)
    chromium fonts-dejavu-core  # the reports opened in a real browser (tests/formats/report/browser_check.py)
  )
  # Node and npm for the independent MCAP reader's tests (tests/formats/mcap); kept when already there (Node 20).
  command -v npm >/dev/null 2>&1 || pkgs+=(nodejs npm)
  local missing=()
  for p in "${pkgs[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p"); done
  if ((${#missing[@]})); then
    echo "setup: installing ${missing[*]}"
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
}

vm() {
  # The machines' kernel has no SocketCAN: the vcan tests run in a QEMU guest (tests/vm/README.md).
  if [[ -x "$here/tests/vm/prepare.sh" ]]; then bash "$here/tests/vm/prepare.sh"; fi
}

build() {
  # Line tables only (-g1): file:line in backtraces, sanitizer reports and perf, no local variables;
  # compiling takes a third less than with -g (docs/performance.md). A debugger session: -g instead.
  cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DHIL_WERROR=ON
  cmake --build "$build" -j "$jobs"
}

case "${1:-}" in
  deps) deps ;;
  vm) vm ;;
  build) deps; build ;;
  demo) deps; build; "$build/tools/hil/hil" demo ;;
  test) deps; vm; build; cd "$build" && ctest -j "$jobs" --output-on-failure --timeout 900 ;;
  *) echo "usage: bash tools/setup.sh demo|test|deps|vm|build" >&2; exit 2 ;;
esac
