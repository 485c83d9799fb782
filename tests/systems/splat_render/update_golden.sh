#!/usr/bin/env bash
# Regenerates the splat renderer's golden images (tests/data/golden/*.png) on this machine's GL driver.
#   tests/systems/splat_render/update_golden.sh [BUILD_DIR]            writes candidates to BUILD_DIR/golden_candidates
#   (look at every candidate with an image viewer; then)
#   tests/systems/splat_render/update_golden.sh [BUILD_DIR] --promote  copies the candidates into tests/data/golden
set -euo pipefail
src="$(cd "$(dirname "$0")/../../.." && pwd)"
build="${1:-$src/build/release}"
[[ "${1:-}" == --promote ]] && build="$src/build/release"
candidates="$build/golden_candidates"
if [[ " $* " == *" --promote "* ]]; then
    ls "$candidates"/*.png > /dev/null
    cp -v "$candidates"/*.png "$src/tests/data/golden/"
    exit 0
fi
rm -rf "$candidates"
SFFD_GOLDEN_CANDIDATES="$candidates" "$build/tests/systems/splat_render/render_gl_tests" --gtest_filter='Golden.*'
echo "candidates in $candidates: review them, then run $0 $build --promote"
