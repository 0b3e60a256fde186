#!/usr/bin/env bash
# check.sh validate|render TUMBLE WORK: `tumble run --gltf` on
# tests/gltf/scene.lua, then
#   validate: the Khronos glTF validator (validate.js) finds no error and
#             no warning in the file, nor in those of an empty world and
#             of one with static shapes only;
#   render:   f3d draws its first frame off-screen (under xvfb-run) from a
#             fixed camera, and render_check.js finds each body where the
#             CSV puts it and background between them.
# A missing tool fails the test with what to install: ./dev.sh test
# installs them all (node and npm, gltf-validator into
# tests/gltf/node_modules, f3d, xvfb, xauth).
set -euo pipefail
mode=$1 tumble=$2 work=$3
here=$(cd "$(dirname "$0")" && pwd)
need() { # command, what installs it
    command -v "$1" > /dev/null || { echo "check.sh: $1 is missing: $2 (./dev.sh test installs it)"; exit 1; }
}
need node "apt-get install nodejs"
rm -rf "$work"
mkdir -p "$work"
cd "$work"
"$tumble" run "$here/scene.lua" --out run.csv --gltf run.glb --quiet
case "$mode" in
validate)
    [ -d "$here/node_modules/gltf-validator" ] ||
        { echo "check.sh: gltf-validator is missing: npm ci --prefix tests/gltf (./dev.sh test runs it)"; exit 1; }
    node "$here/validate.js" run.glb
    # the edges: a world with nothing in it, one with static shapes only
    # (no animation, and no accessors at all in the first)
    printf 'local w = require("tumble").world{}\nreturn { world = w, duration = 0 }\n' > empty.lua
    printf 'local w = require("tumble").world{}\nw:shape{ type = "plane" }\nw:shape{ type = "box", pos = {0, 0, 1} }\nreturn { world = w, duration = 0.1 }\n' > static.lua
    for edge in empty static; do
        "$tumble" run $edge.lua --out $edge.csv --gltf $edge.glb --quiet
        node "$here/validate.js" $edge.glb
    done
    ;;
render)
    need f3d "apt-get install f3d"
    need xvfb-run "apt-get install xvfb xauth"
    # -a: a free display number, so that tests side by side do not collide
    xvfb-run -a -s "-screen 0 640x480x24" f3d run.glb --output=frame.png $(node "$here/render_check.js" f3d-args)
    node "$here/render_check.js" check run.csv frame.png
    ;;
*)
    echo "check.sh: unknown mode '$mode'"
    exit 2
    ;;
esac
