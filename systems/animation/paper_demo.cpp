#include "systems/animation/paper_demo.h"

#include <cassert>
#include <cmath>

#include "systems/animation/editing.h"

namespace sffd {

namespace {

// Rise, hold, fall within [start, start + 1] s: keys at 0, 9/24, 15/24 and 24/24 of the second.
void add_pulse(AnimationTrack& track, double start, const glm::dvec3& peak) {
    const glm::dvec3 zero(0.0);
    set_key(track, {start, zero, Interpolation::linear, Easing::ease_in_out});
    set_key(track, {start + 9.0 / 24.0, peak, Interpolation::linear, Easing::none});
    set_key(track, {start + 15.0 / 24.0, peak, Interpolation::linear, Easing::ease_in_out});
    set_key(track, {start + 1.0, zero, Interpolation::linear, Easing::none});
}

// Control points with i in [i0, i1], j in [j0, j1], k in [k0, k1] (inclusive).
std::vector<std::uint32_t> block(const Lattice& l, glm::ivec3 lo, glm::ivec3 hi) {
    std::vector<std::uint32_t> out;
    for (int i = lo.x; i <= hi.x; ++i)
        for (int j = lo.y; j <= hi.y; ++j)
            for (int k = lo.z; k <= hi.z; ++k) out.push_back(static_cast<std::uint32_t>(l.index(i, j, k)));
    return out;
}

int frac(int n, double f) { return static_cast<int>(std::lround(f * n)); }

}  // namespace

AnimationClip make_paper_demo_clip(const Lattice& lattice) {
    const glm::ivec3 d = lattice.divisions;
    assert(d.x >= 4 && d.y >= 4 && d.z >= 4 && "make_paper_demo_clip(): needs >= 4 divisions per axis");
    // Up is the lattice's T axis (glTF is +Y up and the built-in lattices are axis-aligned boxes); S is
    // "right" and U "front" (the built-in cameras look from +Z).
    const glm::dvec3 up = lattice.axes[1];
    AnimationClip clip;
    clip.name = "paper demo";
    clip.duration = paper_demo_frames / paper_demo_fps;
    clip.mode = PlayMode::loop;

    // 1. Local stretch: an interior block, centred in S and U, in the upper part of T, pulled up.
    {
        const std::size_t t =
            add_stretch_track(clip, "local stretch",
                              block(lattice, {frac(d.x, 0.3), frac(d.y, 0.6), frac(d.z, 0.3)},
                                    {frac(d.x, 0.7), d.y - 1, frac(d.z, 0.7)}));
        add_pulse(clip.tracks[t], 0.0, 0.4 * up);
    }
    // 2. Local twist: the upper right quarter of interior points turns about the up axis through its
    //    rest centroid.
    {
        const std::size_t t = add_twist_track(
            clip, "local twist", block(lattice, {d.x / 2, d.y / 2, 1}, {d.x - 1, d.y - 1, d.z - 1}), up);
        add_pulse(clip.tracks[t], 1.0, glm::dvec3(90.0, 0.0, 0.0));
    }
    // 3. Global stretch: every horizontal layer (constant j) moves along up in proportion to its height
    //    from the middle: the whole lattice stretches by 40%.
    for (int j = 0; j <= d.y; ++j) {
        const std::size_t t = add_stretch_track(clip, "global stretch layer " + std::to_string(j),
                                                block(lattice, {0, j, 0}, {d.x, j, d.z}));
        add_pulse(clip.tracks[t], 2.0, (double(j) / d.y - 0.5) * 0.4 * up);
    }
    // 4. Global twist: every horizontal layer turns about the central vertical axis, the angle
    //    proportional to height (-90 degrees at the bottom, +90 at the top).
    const glm::dvec3 centre = lattice.origin + 0.5 * (lattice.axes[0] + lattice.axes[1] + lattice.axes[2]);
    for (int j = 0; j <= d.y; ++j) {
        const std::size_t t = add_twist_track(clip, "global twist layer " + std::to_string(j),
                                              block(lattice, {0, j, 0}, {d.x, j, d.z}), up, centre);
        add_pulse(clip.tracks[t], 3.0, glm::dvec3((2.0 * j / d.y - 1.0) * 90.0, 0.0, 0.0));
    }
    return clip;
}

}  // namespace sffd
