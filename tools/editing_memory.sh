#!/usr/bin/env bash
# A long editing session stays flat. Replays FRAMES frames (default 10,000) of lattice drags, material
# slider edits (`set material.*` replay lines) and undo/redo on the face scan (content/cache/face.glb; the built-in sphere, with a message, when it is
# absent) in the headless editor at a small target, and compares the peak resident memory of the whole
# run with that of a run of its first 500 frames (the same replay, cut). Prints both; exits 1 when the
# long run's peak is more than 50 MB above the short run's.
#
#   tools/editing_memory.sh [FRAMES]        SPLATFFD=path/to/splatffd overrides the binary
#
# The ctest editor_editing_memory_tests does the same in-process and compares the resident set at frame 500
# with its peak after (SFFD_EDITING_MEMORY_FRAMES=10000 for the long run).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${SPLATFFD:-$root/build/release/tools/splatffd}
frames=${1:-10000}
settle=500
limit_kb=$((50 * 1024))
scene=$root/content/cache/face.glb
if [ ! -f "$scene" ]; then
    echo "editing_memory: $scene not found (tools/fetch_content.sh fetches it); using the built-in sphere" >&2
    scene=sphere
fi
if [ ! -x "$bin" ]; then
    echo "editing_memory: $bin not found (build first, or set SPLATFFD)" >&2
    exit 1
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# Every 20 frames: a drag of the selected control points (6 moves), three material slider edits, and
# undo/redo of both (the drag and the materials end undone).
{
    echo "1 key a shift"  # add a lattice fitted around the cloud (an imported scan has none)
    echo "3 key a ctrl"   # select every control point (the pinned outer layer stays put)
    echo "5 key g"        # move tool
    f=10
    while [ $((f + 20)) -le "$frames" ]; do
        echo "$f move 80 60"
        echo "$((f + 1)) press left"
        for s in 1 2 3 4 5 6; do echo "$((f + 1 + s)) move $((80 + 2 * s)) $((60 - s))"; done
        echo "$((f + 8)) release left"
        c=$((f / 20))
        # off the 0.1 grid: a value equal to the current one is no undo step, and each undo below must
        # undo one of this cycle's steps
        echo "$((f + 9)) set material.specular 0.$((c % 9))5"
        echo "$((f + 10)) set material.shininess $((5 + 8 * (c % 16)))"
        echo "$((f + 11)) set material.base_color.r 0.$((c % 9))5"
        echo "$((f + 12)) key z ctrl"
        echo "$((f + 13)) key y ctrl"
        for s in 14 15 16 17; do echo "$((f + s)) key z ctrl"; done
        echo "$((f + 18)) key y ctrl"
        echo "$((f + 19)) key z ctrl"
        f=$((f + 20))
    done
} >"$tmp/session.txt"

peak_kb() {  # peak resident set (kB) of a headless replay of $1 frames
    /usr/bin/time -f %M -o "$tmp/peak.$1" "$bin" view "$scene" --headless --size 160x120 --quality preview \
        --replay "$tmp/session.txt" --frames "$1" >"$tmp/log.$1" 2>&1 ||
        { echo "editing_memory: the $1-frame replay failed:" >&2; tail -n 20 "$tmp/log.$1" >&2; exit 1; }
    tail -n 1 "$tmp/peak.$1"
}

short=$(peak_kb "$settle")
long=$(peak_kb "$frames")
echo "scene $scene: peak resident memory after $settle frames ${short} kB, after $frames frames ${long} kB" \
    "(growth $(((long - short) / 1024)) MB, limit 50 MB)"
[ $((long - short)) -le "$limit_kb" ]
