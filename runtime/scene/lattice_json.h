// The one JSON form of a lattice, read and written here for both places lattices are stored: lattice
// files (systems/ffd/lattice_io.h, `splatffd deform --lattice`) and scene files (each entry of
// SFFD_scene "lattices", runtime/assets/scene.cpp, which handles its own "id", "name" and "transform"
// keys and hands the rest here).
//
//   {"origin":[x,y,z], "axes":[[Sx,Sy,Sz],[Tx,Ty,Tz],[Ux,Uy,Uz]], "divisions":[l,m,n],
//    "basis":"bernstein"|"bspline", "control_points":[[x,y,z],...], "rest_control_points":[[x,y,z],...]}
//
// "basis" is optional (bernstein). "control_points" is optional or null (absent = rest).
// "rest_control_points" is optional (absent = the uniform grid rest_grid()); it is written whenever the
// rest differs from that grid in any bit, so a lattice reads back exactly as it was written.
// Older scene files name the same points "current" and "rest" and store them flat
// ([x0,y0,z0, x1,y1,z1, ...]): both names and both shapes are read, for either set of points.
// Reading refuses unknown keys (a misspelt "controlpoints" would silently deform nothing), missing keys,
// wrong counts, non-numbers, numbers above kMaxLatticeCoordinate in magnitude, and everything
// validate_lattice() refuses. Messages read `where: problem`.
#pragma once

#include <string>

#include <nlohmann/json_fwd.hpp>

#include "runtime/core/result.h"
#include "runtime/scene/lattice.h"

namespace sffd {

// Control points larger than this overflow when the basis sums them (1e308 passed as finite and deformed
// to inf); 1e30 leaves room for every product and sum in double and in the float paths' offsets.
inline constexpr double kMaxLatticeCoordinate = 1e30;

// `where` starts every message (a file name, or e.g. "scene.glb: SFFD_scene lattice").
Result<Lattice> lattice_from_json(const nlohmann::json& j, const std::string& where);

// Doubles are written so that they read back to the same bits.
nlohmann::json lattice_to_json(const Lattice& lattice);

}  // namespace sffd
