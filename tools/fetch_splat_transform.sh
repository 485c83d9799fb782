#!/usr/bin/env bash
# Installs @playcanvas/splat-transform (MIT, an independent Gaussian-splat converter) for the interop tests
# (tests/systems/gaussian/splat_transform_test.cpp, label `slow`). Lands in content/cache/splat-transform
# (gitignored), or $SPLATFFD_CACHE_DIR/splat-transform. Install scripts are not run (the optional webgpu
# renderer is not needed for file conversion). The package declares node >= 22; its converters run on
# node 20 here (tested with 3.7.0).
# Usage: tools/fetch_splat_transform.sh [version]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cache="${SPLATFFD_CACHE_DIR:-$root/content/cache}"
version="${1:-3.7.0}"
command -v npm >/dev/null || { echo "fetch_splat_transform.sh: npm not found" >&2; exit 1; }
mkdir -p "$cache/splat-transform"
npm install --prefix "$cache/splat-transform" --no-audit --no-fund --ignore-scripts "@playcanvas/splat-transform@$version"
"$cache/splat-transform/node_modules/.bin/splat-transform" --version
