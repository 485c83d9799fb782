// The built-in demo clip: the paper's four cases (Beddiaf & Babahenini, Figs. 3-6 / 8-11) in sequence,
// 96 frames at 24 fps (4 s, looping), one second per case:
// "Up" is the lattice's T axis (glTF +Y up; the built-in lattices are axis-aligned boxes):
//   frames  0-23  local stretch   an interior block in the upper middle pulled up by 0.4 T
//   frames 24-47  local twist     the upper right quarter of interior points turned 90 deg about T
//                                 through its rest centroid
//   frames 48-71  global stretch  every control point; layer j moves by (j/m - 1/2) * 0.4 T, so the
//                                 object lengthens by 40% along T (one stretch track per layer)
//   frames 72-95  global twist    every control point; layer j turns by (2j/m - 1) * 90 deg about the
//                                 lattice's central T axis (one twist track per layer, shared pivot)
// Local cases never touch the outer layer of control points (pinned: no seam where the surface leaves
// the box). Each case eases in over 9 frames, holds its peak from frame 9 to 15 of its second, and eases
// back to rest by the next case. Directions and sizes come from the lattice's axes, so the clip fits any
// lattice with at least 4 divisions per axis (the built-in scenes use 10: 11x11x11 control points).
#pragma once

#include "systems/animation/components.h"
#include "systems/ffd/components.h"

namespace sffd {

inline constexpr double paper_demo_fps = 24.0;
inline constexpr int paper_demo_frames = 96;

AnimationClip make_paper_demo_clip(const Lattice& lattice);

}  // namespace sffd
