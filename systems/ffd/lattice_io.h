// Lattice JSON files (the `splatffd deform --lattice` format): the one JSON form of a lattice
// (runtime/scene/lattice_json.h, shared with scene files), read from a file or a string:
//   {"origin":[x,y,z], "axes":[[Sx,Sy,Sz],[Tx,Ty,Tz],[Ux,Uy,Uz]], "divisions":[l,m,n],
//    "basis":"bernstein"|"bspline", "control_points":[[x,y,z],...]}
// control_points optional (absent = rest), (l+1)(m+1)(n+1) of them, index (i*(m+1)+j)*(n+1)+k.
// Extension: optional "rest_control_points" (same shape) for a lattice whose rest was set by
// apply_as_rest(); absent = the uniform grid. Errors name the file and the problem.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "runtime/core/result.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

// `name` is used in error messages (a path, or e.g. "<string>").
Result<Lattice> parse_lattice_json(std::string_view text, const std::string& name);
Result<Lattice> load_lattice(const std::filesystem::path& path);
// Atomic (temp + rename).
Status save_lattice(const std::filesystem::path& path, const Lattice& lattice);

}  // namespace sffd::ffd
