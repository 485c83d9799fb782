// The built-in demo clip: the paper's four cases (Beddiaf & Babahenini, Figs. 3-6 / 8-11) in sequence,
// 96 frames at 24 fps (4 s, looping), one second per case:
//   frames  0-23  local stretch   a block of interior control points in the upper middle pulled by 0.5 U
//   frames 24-47  local twist     the upper front quadrant of interior points turned 90 deg about U
//                                 through its rest centroid
//   frames 48-71  global stretch  every control point; layer k moves by (k/n - 1/2) * 0.6 U, so the
//                                 object lengthens by 60% along U (one stretch track per layer)
//   frames 72-95  global twist    every control point; layer k turns by (2k/n - 1) * 90 deg about the
//                                 lattice's central U axis (one twist track per layer, shared pivot)
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
