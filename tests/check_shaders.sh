#!/usr/bin/env bash
# Validates every shader in the variants the engine compiles with glslangValidator (OpenGL 4.5 semantics,
# then SPIR-V for OpenGL), the way the engine compiles them: defines injected after #version, #include
# resolved against shaders/. A second, strict compiler beside the one driver the tests run on (llvmpipe),
# which accepts some GLSL that others refuse. Exit 77 (skipped) without glslangValidator.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)/shaders"
if ! command -v glslangValidator > /dev/null; then
    echo "glslangValidator not found (Debian package glslang-tools): shaders not checked"; exit 77
fi
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
status=0
check() {  # file stage defines...
    local file="$1" stage="$2"; shift 2
    local out="$tmp/$(basename "$file").$stage"
    echo "$file" >> "$tmp/checked"
    { head -n1 "$root/$file"; echo "#extension GL_GOOGLE_include_directive : require"
      for d in "$@"; do echo "#define ${d%%=*} ${d#*=}"; done
      tail -n +2 "$root/$file"; } > "$out"
    if ! glslangValidator ${SPIRV--G -o "$tmp/out.spv"} -S "$stage" -I"$root" -I"$root/$(dirname "$file")" "$out" > "$tmp/log" 2>&1; then
        echo "FAIL $file $*"; cat "$tmp/log"; status=1
    else
        echo "ok   $file $*"
    fi
}
# The variants init_render_state compiles: visibility (pass 0) and attribute (pass 1) without the
# auxiliary outputs, preview (pass 2) with and without.
for shape in 0 1; do
    check splat_render/splat.vert vert SHAPE_QUAD=$shape PASS=0 AUX=0
    check splat_render/splat.vert vert SHAPE_QUAD=$shape PASS=1 AUX=0
    for a in 0 1; do check splat_render/splat.vert vert SHAPE_QUAD=$shape PASS=2 AUX=$a; done
done
for q in 0 1; do check splat_render/visibility.frag frag SHAPE_QUAD=$q PASS=0; done
for q in 0 1; do for m in 0 1; do for t in 0 1; do check splat_render/attribute.frag frag SHAPE_QUAD=$q PASS=1 MATERIALS=$m TEXTURED=$t; done; done; done
for shape in 0 1; do check splat_render/splat.vert vert SHAPE_QUAD=$shape PASS=1 AUX=0 TEXTURED=1; done
for shape in 0 1; do for a in 0 1; do check splat_render/splat.vert vert SHAPE_QUAD=$shape PASS=2 AUX=$a TEXTURED=1; done; done
for q in 0 1; do for a in 0 1; do check splat_render/preview.frag frag SHAPE_QUAD=$q PASS=2 AUX=$a TEXTURED=1; done; done
for q in 0 1; do for a in 0 1; do check splat_render/preview.frag frag SHAPE_QUAD=$q PASS=2 AUX=$a; done; done
for m in 0 1; do for l in 0 1 2 3 4; do check splat_render/shade.frag frag LIGHTS=$l MATERIALS=$m; done; done
check splat_render/fullscreen.vert vert
check splat_render/cull.comp comp
for t in 0 1; do for l in 0 1; do check splat_render/cull.comp comp TEXTURED=$t LIT=$l LIGHTS=$((l * 2)); done; done
check splat_render/compute_visibility.comp comp
for t in 0 1; do check splat_render/compute_attribute.comp comp TEXTURED=$t; done
check splat_render/compute_merge.frag frag
check splat_render/compute_resolve.frag frag
check splat_render/display.frag frag
# The Gaussian shaders use plain (location-less) uniforms, which SPIR-V for OpenGL (-G) refuses unless
# locations are assigned automatically (--aml; the GL driver assigns its own).
SPIRV="-G --aml -o $tmp/out.spv"
for f in splat_render/gaussian/project.comp:comp splat_render/gaussian/splat.vert:vert splat_render/gaussian/splat.frag:frag \
         splat_render/gaussian/tile_count.comp:comp splat_render/gaussian/tile_emit.comp:comp splat_render/gaussian/tile_ranges.comp:comp \
         splat_render/gaussian/tile_blend.comp:comp gaussian/deform.comp:comp splat_render/gaussian/sort_payload.comp:comp splat_render/gaussian/gather.comp:comp splat_render/gaussian/marks.comp:comp \
         common/radix_sort_count.comp:comp common/radix_sort_scan.comp:comp common/radix_sort_scatter.comp:comp \
         common/scan_reduce.comp:comp common/scan_add.comp:comp \
         splat_render/gaussian/accum.frag:frag splat_render/gaussian/composite.frag:frag; do
    check "${f%%:*}" "${f##*:}"
done
check editor/lattice.vert vert
check editor/lattice.frag frag
check editor/lattice_cache.frag frag
for d in 0 1; do check ffd/paper_mode.vert vert PAPER_DEFORM=$d; done
check ffd/paper_mode.frag frag
# The deform shaders as DeformPrograms compiles them (systems/ffd/gpu_kernel.cpp): generic, and per lattice
# shape (11^3 here) for each control-point kernel: Bernstein from shared memory (256 wide), a UBO or the
# SSBO; B-spline in runs along u, from shared memory or point by point. The Gaussian one also per output
# combination (frames, coefficients). Bernstein also summing one or two moving coordinates (FFD_MOVE).
lattice="FFD_L=10 FFD_M=10 FFD_N=10 FFD_MAXB=11"
one="FFD_MOVE=y FFD_MOVE_N=1 FFD_MOVE_A=1"
two="FFD_MOVE=xz FFD_MOVE_N=2 FFD_MOVE_A=0 FFD_MOVE_B=2"
kernels=("FFD_BASIS=0 FFD_CP_SHARED=1331 FFD_LOCAL_SIZE=256" "FFD_BASIS=0 FFD_CP_UBO=1331" "FFD_BASIS=0"
         "FFD_BASIS=0 FFD_CP_SHARED=1331 FFD_LOCAL_SIZE=256 $one" "FFD_BASIS=0 FFD_CP_UBO=1331 $two"
         "FFD_BASIS=0 $one" "FFD_BASIS=0 FFD_CP_SHARED=1331 FFD_LOCAL_SIZE=256 $two"
         "FFD_BASIS=1 FFD_BSPLINE_RUNS=1" "FFD_BASIS=1 FFD_CP_SHARED=2197 FFD_LOCAL_SIZE=256" "FFD_BASIS=1")
for shader in ffd/deform.comp gaussian/deform.comp; do
    check $shader comp
    for k in "${kernels[@]}"; do
        # shellcheck disable=SC2086 # one define per word
        if [ $shader = ffd/deform.comp ]; then check $shader comp $lattice $k; continue; fi
        for frames in 0 1; do for sh in 0 1; do
            # shellcheck disable=SC2086
            check $shader comp $lattice $k GAUSS_FRAMES=$frames GAUSS_SH=$sh
        done; done
    done
done
# Every shader file is checked at least once: a new one cannot be left out unnoticed.
for f in $(cd "$root" && find . -name '*.vert' -o -name '*.frag' -o -name '*.comp' | sed 's|^\./||' | sort); do
    grep -qx "$f" "$tmp/checked" || { echo "FAIL $f: not checked by this script"; status=1; }
done
exit $status
