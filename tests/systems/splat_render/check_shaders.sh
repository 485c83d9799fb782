#!/usr/bin/env bash
# Validates every splat_render shader variant with glslangValidator (OpenGL 4.5 semantics), the way the
# render system compiles them: defines injected after #version, #include resolved against shaders/.
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)/shaders"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
status=0
check() {  # file stage defines...
    local file="$1" stage="$2"; shift 2
    local out="$tmp/$(basename "$file").$stage"
    { head -n1 "$root/$file"; echo "#extension GL_GOOGLE_include_directive : require"
      for d in "$@"; do echo "#define ${d%%=*} ${d#*=}"; done
      tail -n +2 "$root/$file"; } > "$out"
    if ! glslangValidator ${SPIRV--G -o "$tmp/out.spv"} -S "$stage" -I"$root" -I"$root/$(dirname "$file")" "$out" > "$tmp/log" 2>&1; then
        echo "FAIL $file $*"; cat "$tmp/log"; status=1
    else
        echo "ok   $file $*"
    fi
}
for shape in 0 1; do for pass in 0 1 2; do for a in 0 1; do check splat_render/splat.vert vert SHAPE_QUAD=$shape PASS=$pass AUX=$a; done; done; done
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
# The Gaussian shaders use plain (location-less) uniforms, which SPIR-V for OpenGL (-G) refuses unless
# locations are assigned automatically (--aml; the GL driver assigns its own).
SPIRV="-G --aml -o $tmp/out.spv"
for f in gaussian/project.comp:comp gaussian/splat.vert:vert gaussian/splat.frag:frag \
         gaussian/tile_count.comp:comp gaussian/tile_emit.comp:comp gaussian/tile_ranges.comp:comp \
         gaussian/tile_blend.comp:comp gaussian/deform.comp:comp gaussian/sort_payload.comp:comp \
         common/radix_sort_count.comp:comp common/radix_sort_scan.comp:comp common/radix_sort_scatter.comp:comp \
         common/scan_reduce.comp:comp common/scan_add.comp:comp \
         splat_render/gaussian_accum.frag:frag splat_render/gaussian_composite.frag:frag; do
    check "${f%%:*}" "${f##*:}"
done
exit $status
