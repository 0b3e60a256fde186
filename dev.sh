#!/usr/bin/env bash
# dev.sh: set up, build, run and test tumble on Debian 12.
#
#   ./dev.sh run     install what is missing, build, run the default scene
#   ./dev.sh test    install what is missing, build, run the whole test suite
#   ./dev.sh asan    the same suite built with AddressSanitizer + UBSan
#   ./dev.sh bench   build and run the benchmarks (not part of the tests)
#   ./dev.sh charts  rerun the work-precision benchmark and redraw docs/charts
#
# Warnings are errors when CI is set (CI=true), as in .ci/run.
set -euo pipefail
cd "$(dirname "$0")"

packages=(build-essential cmake pkg-config liblua5.4-dev lua5.4 libcmocka-dev libode-dev gnuplot-nox)

install_missing() {
    local missing=() p sudo=""
    for p in "${packages[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    ((${#missing[@]})) || return 0
    [ "$(id -u)" -eq 0 ] || sudo=sudo
    echo "dev.sh: installing ${missing[*]}"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

build() { # preset
    local werror=OFF
    [ "${CI:-}" = "true" ] && werror=ON
    cmake --preset "$1" -DTUMBLE_WERROR="$werror" > /dev/null
    cmake --build --preset "$1"
}

case "${1:-}" in
run)
    install_missing
    build default
    ./build/default/tumble run scenes/projectile.lua --out projectile.csv
    ;;
test)
    install_missing
    build default
    ctest --preset default
    ;;
asan)
    install_missing
    build asan
    ctest --preset asan
    ;;
bench)
    install_missing
    build default
    ./build/default/bench/bench_particles
    ./build/default/bench/bench_bodies
    ./build/default/bench/bench_rotation
    ./build/default/bench/bench_contacts
    ./build/default/bench/bench_robustness
    ./build/default/bench/bench_snapshot
    ;;
charts)
    install_missing
    build default
    mkdir -p bench/out
    ./build/default/bench/bench_workprecision bench/out
    gnuplot bench/workprecision.gp
    ;;
*)
    sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
    ;;
esac
