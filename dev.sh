#!/usr/bin/env bash
# dev.sh: set up, build, run and test tumble on Debian 12.
#
#   ./dev.sh run     install what is missing, build, run the default scene
#   ./dev.sh test    install what is missing, build, run the whole test suite
#   ./dev.sh asan    the same suite built with AddressSanitizer + UBSan
#   ./dev.sh fuzz    the libFuzzer targets under ASan + UBSan, FUZZ_SECONDS
#                    (default 60) each, from fuzz/corpus (needs Clang)
#   ./dev.sh bench   build and run the benchmarks (not part of the tests)
#   ./dev.sh charts  rerun the work-precision and contact-scaling benchmarks
#                    and redraw docs/charts
#
# Warnings are errors when CI is set (CI=true), as in .ci/run.
set -euo pipefail
cd "$(dirname "$0")"

# What building the library and the command and running a scene needs;
# the tests, benchmarks and charts need the rest. The suite also needs what
# the glTF tests run (tests/gltf/check.sh): f3d to render a frame, xvfb and
# xauth for its off-screen display (xvfb-run), Mesa's software OpenGL, and
# node with npm for the Khronos validator (install_node).
run_packages=(build-essential cmake pkg-config liblua5.4-dev)
packages=("${run_packages[@]}" lua5.4 libcmocka-dev libode-dev libbullet-dev gnuplot-nox)
test_packages=("${packages[@]}" f3d xvfb xauth libgl1-mesa-dri)

install_missing() { # packages
    local missing=() p sudo=""
    for p in "$@"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    ((${#missing[@]})) || return 0
    [ "$(id -u)" -eq 0 ] || sudo=sudo
    echo "dev.sh: installing ${missing[*]}"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# node and npm (Debian's, unless a node with npm is there already), then
# gltf-validator into tests/gltf/node_modules at the version
# tests/gltf/package-lock.json pins. A failure stops here: the tests need it.
install_node() {
    command -v node > /dev/null && command -v npm > /dev/null || install_missing nodejs npm
    node -e 'process.exit(require("./tests/gltf/node_modules/gltf-validator/package.json").version ===
             require("./tests/gltf/package.json").dependencies["gltf-validator"] ? 0 : 1)' 2> /dev/null && return 0
    echo "dev.sh: installing gltf-validator into tests/gltf/node_modules"
    npm ci --prefix tests/gltf --no-audit --no-fund --loglevel=error
}

build() { # preset
    local werror=OFF
    [ "${CI:-}" = "true" ] && werror=ON
    cmake --preset "$1" -DTUMBLE_WERROR="$werror" > /dev/null
    cmake --build --preset "$1"
}

case "${1:-}" in
run)
    install_missing "${run_packages[@]}"
    build run
    ./build/default/tumble run scenes/projectile.lua --out projectile.csv
    ;;
test)
    install_missing "${test_packages[@]}"
    install_node
    build default
    ctest --preset default
    ;;
asan)
    install_missing "${test_packages[@]}"
    install_node
    build asan
    ctest --preset asan
    ;;
fuzz)
    install_missing "${packages[@]}" clang-14 libclang-rt-14-dev
    build fuzz
    # Each target runs on a copy of its seed corpus and regressions; an input
    # that fails is left as crash-*, leak-* or timeout-* in the work folder,
    # and belongs in fuzz/regressions/<target>/ once fixed.
    work=$(mktemp -d)
    status=0
    for target in fuzz_api fuzz_scene; do
        mkdir -p "$work/$target"
        cp fuzz/corpus/$target/* fuzz/regressions/$target/* "$work/$target/" 2>/dev/null || true
        if [ "$target" = fuzz_scene ]; then cp scenes/*.lua "$work/$target/"; fi
        dict=()
        [ -f fuzz/$target.dict ] && dict=(-dict=fuzz/$target.dict)
        echo "dev.sh: $target for ${FUZZ_SECONDS:-60} s"
        ./build/fuzz/fuzz/$target "$work/$target" "${dict[@]}" -max_total_time="${FUZZ_SECONDS:-60}" \
            -timeout=20 -rss_limit_mb=2048 -artifact_prefix="$work/" -print_final_stats=1 2>&1 |
            grep -E "^(stat::number_of_executed_units|==[0-9]+==ERROR|SUMMARY)" || true
        if [ -n "$(find "$work" -maxdepth 1 \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \))" ]; then
            echo "dev.sh: $target found failing inputs in $work" >&2
            status=1
            break
        fi
    done
    [ "$status" -eq 0 ] && rm -rf "$work"
    exit "$status"
    ;;
bench)
    install_missing "${packages[@]}"
    build default
    ./build/default/bench/bench_particles
    ./build/default/bench/bench_lua_force
    ./build/default/bench/bench_bodies
    ./build/default/bench/bench_rotation
    ./build/default/bench/bench_contacts
    ./build/default/bench/bench_robustness
    ./build/default/bench/bench_joints
    ./build/default/bench/bench_snapshot
    ;;
charts)
    install_missing "${packages[@]}"
    build default
    mkdir -p bench/out
    ./build/default/bench/bench_workprecision bench/out
    gnuplot bench/workprecision.gp
    ./build/default/bench/bench_contacts --scaling bench/out
    gnuplot bench/contact_scaling.gp
    ;;
*)
    sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
    ;;
esac
