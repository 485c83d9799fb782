#!/usr/bin/env bash
# The README's "Try it" block, as a new user runs it: extracted from README.md and run top to bottom by
# bash (-e: the first failing step fails the test) in an empty temporary folder, with S set to the built
# binary. The editor step runs two headless frames instead of opening a window; a `fetch` that cannot
# reach a registry skips the steps chained after it with && and says so. Then a few of the results are
# checked, so a step that "succeeds" without doing its work is caught too.
# usage: readme_walk_test.sh <source-dir> <splatffd>
set -euo pipefail
src=$1
exe=$2
readme="$src/README.md"
# The first ```sh block after the "## Try it" heading.
block=$(awk '/^## Try it/ { on = 1; next } on && /^```sh/ { inb = 1; next } inb && /^```/ { exit } inb { print }' "$readme")
[[ -n $block ]] || { echo "readme_walk_test: no \`\`\`sh block under '## Try it' in $readme"; exit 1; }
grep -q '^S=' <<<"$block" || { echo "readme_walk_test: the block does not set S= (the command)"; exit 1; }
if ! command -v ffmpeg >/dev/null 2>&1; then
  echo "readme_walk_test: skipped: ffmpeg is not installed (tools/bootstrap.sh installs it; the walk's --video step needs it)"
  exit 77
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# S names the built binary; `$S view ARGS  # comment` becomes `$S view ARGS --headless --frames 2  # comment`.
sed -e "s|^S=.*|S=$exe|" -e 's|^\(\$S view [^#]*[^# ]\)|\1 --headless --frames 2|' <<<"$block" >"$tmp/walk.sh"
echo "readme_walk_test: running in $tmp:"
cat "$tmp/walk.sh"
echo "----"
cd "$tmp"
if ! env -u DISPLAY -u WAYLAND_DISPLAY bash -e -x walk.sh >walk.log 2>&1; then
  cat walk.log
  echo "readme_walk_test: the walk failed at the step above"
  exit 1
fi
cat walk.log

fail() { echo "readme_walk_test: $*"; exit 1; }
[[ -f out/clip/frame_0095.png && -f out/clip/frame_0084.exr ]] || fail "render wrote no out/clip/frame_0095.png"
grep -q '^psnr_db=' walk.log || fail "compare printed no psnr_db= line"
psnr=$(sed -n 's/^psnr_db=\([0-9.]*\).*/\1/p' walk.log | head -1)
awk -v p="$psnr" 'BEGIN { exit !(p >= 20) }' || fail "the clip's frame 84 is $psnr dB from the reference (expected >= 20: the clip plays)"
[[ -s out/turn.mp4 ]] || fail "no out/turn.mp4"
[[ -f out/cam/frame_0000.png && -f out/turn/frame_0047.png && -f out/g/frame_0023.png ]] || fail "a render step wrote no frames"
grep -q '"hit": *true' walk.log || grep -q '"hit":true' walk.log || fail "pick printed no hit"
grep -q 'deformed by 1 lattice' walk.log || fail "deform said nothing about the lattice"
cmp -s out/scan.ply out/bent.ply && fail "out/bent.ply is the undeformed scan"
cmp -s out/g.ply out/gt.ply && fail "out/gt.ply is the undeformed Gaussians"
[[ -s out/profile.json ]] || fail "profile wrote no out/profile.json"
if [[ -f out/face/frame_0000.png ]]; then
  echo "readme_walk_test: every step ran, the face scan included"
else
  echo "readme_walk_test: every step ran; fetch could not reach a registry, so the face scan step was skipped"
fi
