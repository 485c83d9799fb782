// `splatffd deform IN OUT` with a level-of-detail hierarchy on both sides: a streamed SOG
// (DIR/lod-meta.json) into a streamed SOG, a Potree 2 octree of our splats (DIR/metadata.json) into one.
// IN's finest detail is read one piece at a time (a level-0 unit; an octree node, every node together
// being the finest detail), deformed by the lattices in order on the CPU, and fed to OUT's builder
// (runtime/assets/formats/lod/lod_build.h, surface/potree2_write.h), which merges the Gaussians' parents
// or subsamples the splats' representatives again from the deformed points: the coarse levels are those
// of the deformed shape, not the old ones moved. Memory: one piece plus the builder's budget, whatever the
// size. The lattices are in the files' frame (as deform takes them for any file); a fit spec is fitted to
// the root's box.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"

namespace sffd::cli {

struct LatticeChain;

// OUT (or IN) names a hierarchy: a lod-meta.json or a metadata.json.
bool is_hierarchy_path(const std::string& path);

// The lattices for points `positions` (relative to `origin`): deform's own rule (--lattice, a fit spec).
using ChainFor =
    std::function<Result<LatticeChain>(const std::vector<glm::vec3>& positions, const glm::dvec3& origin)>;

// Returns the exit code; messages name the file.
int deform_hierarchy(const std::string& in, const std::string& out, const ChainFor& chain);

}  // namespace sffd::cli
