#!/usr/bin/env bash
# Install test: `cmake --install` into a temporary prefix, then run the installed binary from an unrelated
# directory with no source tree in reach: it must find its shaders and content under
# <prefix>/share/splatffd (runtime/core/paths.cpp), and a command that loads shaders must work.
# usage: install_test.sh <build-dir>
set -euo pipefail
build=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
cmake --install "$build" --prefix "$prefix" >"$tmp/install.log"
exe="$prefix/bin/splatffd"
[[ -x $exe ]] || { echo "install_test: $exe was not installed"; exit 1; }
[[ -f $prefix/share/splatffd/shaders/common/bindings.h ]] || { echo "install_test: shaders not installed"; exit 1; }
[[ -d $prefix/share/splatffd/content ]] || { echo "install_test: content/ not installed"; exit 1; }

mkdir -p "$tmp/elsewhere" && cd "$tmp/elsewhere"
# Hide the source tree's data from the binary: only the installed copy may be found.
unset SPLATFFD_DATA_DIR
version=$("$exe" --version)
[[ $version == "splatffd "* ]] || { echo "install_test: --version printed '$version'"; exit 1; }
paths=$("$exe" --paths)
echo "$paths"
shaders=$(sed -n 's/^shaders //p' <<<"$paths")
content=$(sed -n 's/^content //p' <<<"$paths")
[[ $(realpath "$shaders") == $(realpath "$prefix/share/splatffd/shaders") ]] ||
  { echo "install_test: installed binary uses shaders from $shaders, not the install prefix"; exit 1; }
[[ $(realpath "$content") == $(realpath "$prefix/share/splatffd/content") ]] ||
  { echo "install_test: installed binary uses content from $content, not the install prefix"; exit 1; }

# A command that compiles the engine's shaders, from the installed data (once `render` has landed).
if help=$("$exe" render --help 2>&1) || ! grep -q "not implemented yet" <<<"$help"; then
  "$exe" render sphere --out "$tmp/frames" --frames 0:0 --size 64x48 --format png
  n=$(find "$tmp/frames" -name '*.png' | wc -l)
  ((n == 1)) || { echo "install_test: installed render wrote $n PNG files, expected 1"; exit 1; }
  echo "install_test: installed render wrote $(find "$tmp/frames" -name '*.png')"
else
  echo "install_test: 'render' not implemented yet; checked --version and data paths only"
fi
# The `face` scene's cache is made by tools/fetch_content.sh, which is installed with its helper;
# the installed binary's message names the installed script, and that script uses the installed binary
# and the cache that binary reads (no source tree, no build).
script="$prefix/share/splatffd/tools/fetch_content.sh"
[[ -x $script ]] || { echo "install_test: $script was not installed (or is not executable)"; exit 1; }
[[ -f $prefix/share/splatffd/tools/fetch_content/snowden_to_obj.js ]] ||
  { echo "install_test: fetch_content/snowden_to_obj.js not installed"; exit 1; }
export XDG_CACHE_HOME="$tmp/xdg-cache"  # an empty cache, whichever folder the binary picks
if face=$("$exe" render face --out "$tmp/face" --frames 0:0 --size 64x48 --format png 2>&1); then
  echo "install_test: 'render face' succeeded without the face cache: $face"; exit 1
fi
grep -qF "run $(realpath "$script") once" <<<"$face" || grep -qF "run $script once" <<<"$face" ||
  { echo "install_test: 'render face' does not name the installed $script: $face"; exit 1; }
echo "install_test: render face says: $face"
where=$("$script" --where)
[[ $(sed -n 's/^splatffd //p' <<<"$where") -ef $exe ]] ||
  { echo "install_test: installed fetch_content.sh would use another splatffd: $where"; exit 1; }
[[ $(sed -n 's/^cache //p' <<<"$where") -ef $(sed -n 's/^cache //p' <<<"$("$exe" --paths)") ]] ||
  { echo "install_test: installed fetch_content.sh writes to another cache than the binary reads: $where"; exit 1; }

# `splatffd fetch` runs that installed script with the installed binary.
fetch_where=$("$exe" fetch --where)
[[ $(sed -n 's/^splatffd //p' <<<"$fetch_where") -ef $exe && $(sed -n 's/^cache //p' <<<"$fetch_where") -ef $(sed -n 's/^cache //p' <<<"$where") ]] ||
  { echo "install_test: 'splatffd fetch --where' printed '$fetch_where', the script '$where'"; exit 1; }

echo "install_test: ok"
