#!/usr/bin/env bash
# consumers.sh BUILD_DIR SOURCE_DIR: installs the build into a scratch
# prefix and builds and runs a small program against it three ways (the
# CMake package, pkg-config with the default static library, and
# add_subdirectory of the source tree), compiles the public headers as
# C++, and has a stock lua5.4 require the installed module. Run by ctest as install.consumers (docs/testing.md).
set -euo pipefail
build=$(cd "$1" && pwd) source=$(cd "$2" && pwd) here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" > /dev/null

echo "== find_package"
cmake -S "$here/find_package" -B "$work/fp" -DCMAKE_PREFIX_PATH="$work/prefix" > /dev/null
cmake --build "$work/fp" > /dev/null
"$work/fp/app"

echo "== pkg-config"
pc=$(find "$work/prefix" -name tumble.pc)
export PKG_CONFIG_PATH=$(dirname "$pc")
libdir=$(dirname "$PKG_CONFIG_PATH")
# shellcheck disable=SC2046
cc -std=c99 "$here/app.c" -o "$work/pc_app" $(pkg-config --cflags --libs tumble)
"$work/pc_app"

echo "== add_subdirectory"
cmake -S "$here/subdirectory" -B "$work/sub" -DTUMBLE_SOURCE="$source" > /dev/null
cmake --build "$work/sub" -j2 > /dev/null
"$work/sub/app"

echo "== headers as C++"
lua_cflags=$(pkg-config --cflags lua5.4 2>/dev/null || true)
# shellcheck disable=SC2086
c++ -std=c++11 -Wall -Wextra -Wpedantic -Werror -I"$work/prefix/include" $lua_cflags "$here/headers.cpp" \
    -L"$libdir" -ltumble_lua -ltumble $(pkg-config --libs lua5.4) -lm -o "$work/cxx_app"
"$work/cxx_app"
echo "== lua5.4 requires the installed module"
module=$(find "$work/prefix" -name tumble.so)
LUA_CPATH="$(dirname "$module")/?.so" lua5.4 "$here/../lua/require_module.lua" "$(pkg-config --modversion tumble)"
echo "consumers: all built and ran"
