// Half-size in pixels, per axis, of the box around a projected Gaussian's centre that holds every pixel
// it can be seen in. The reference's box is the 3σ square of radius r. Within it, only the ellipse
// dᵀ Q d <= 2 ln(255 o) reaches α >= 1/255 (the blend skips the rest): its bounding box has half-widths
// sqrt(2 ln(255 o) Σxx) and sqrt(2 ln(255 o) Σyy), Σ = Q⁻¹, widened by a margin for rounding. A thin
// Gaussian seen across the image's axes, or a faint one, covers a fraction of the square. Where Q is
// nearly singular relative to its diagonal (thin and near 45°, where that box is close to the square
// anyway) Σ is not taken from it. The quads, the tiles and the coverage count all use this box, so the
// same pixels are drawn as with the square and the coverage counts what is drawn.
#ifndef SFFD_GAUSS_FOOTPRINT_GLSL
#define SFFD_GAUSS_FOOTPRINT_GLSL

// r: the 3σ radius (proj_center's w); q: the conic Q = Σ⁻¹ (xx, xy, yy) and the opacity (proj_conic).
vec2 footprint_half_size(float r, vec4 q) {
    vec2 half_size = vec2(r);
    const float qdet = q.x * q.z - q.y * q.y;
    if (qdet > 1e-2 * q.x * q.z) {
        const float k = 2.0 * log(255.0 * q.w);
        const vec2 e = sqrt(max(k, 0.0) * vec2(q.z, q.x) / qdet) * 1.001 + 0.01;
        half_size = min(half_size, e);
    }
    return half_size;
}

#endif
