// Potree 2 octrees of surface splats (PotreeConverter 2's layout, read by potree's
// src/modules/loader/2.0/OctreeLoader.js), read and checked here; written by potree2_write.h.
//
//   DIR/metadata.json  {"version": "2.0", "name", "description", "points": N, "projection": "",
//                       "hierarchy": {"firstChunkSize": bytes, "stepSize": 4, "depth": D},
//                       "offset": [3], "scale": [3], "spacing": s, "boundingBox": {"min": [3], "max": [3]},
//                       "encoding": "DEFAULT", "attributes": [{"name", "description", "size", "numElements",
//                       "elementSize", "type", "min": [..], "max": [..]}, ...],
//                       "sffd": {"origin": [3], "texture": "texture.png"} (ours; Potree ignores it)}
//   DIR/hierarchy.bin  22-byte node records, little-endian: uint8 type (0 inner, 1 leaf, 2 proxy), uint8
//                      childMask (bit i: child i = x·4 + y·2 + z, the upper half along each set bit),
//                      uint32 numPoints, int64 byteOffset, int64 byteSize. Chunks of stepSize levels: a
//                      chunk lists its root and every descendant down to stepSize levels below it in
//                      breadth-first order (children in child order); the nodes on its last level are
//                      proxies whose byteOffset/byteSize name their own chunk in hierarchy.bin, whose first
//                      record is that node again with its real type and points. The root's chunk is at 0,
//                      firstChunkSize bytes long.
//   DIR/octree.bin     each node's points back to back at its byteOffset, byteSize = numPoints · the
//                      attributes' sizes; a point's attributes in the order listed.
// Node boxes follow from boundingBox (a cube) by halving; position is int32 x 3 with the world position
// int · scale + offset. Every point is in exactly one node: an inner node holds a subsample of its subtree
// (the representatives), and the full detail is the union of all nodes.
//
// Attributes we write: "position" (int32 x 3), "rgb" (uint16 x 3, 8-bit sRGB · 257, as Potree reads it),
// "alpha" (uint8, only when some splat is not opaque), "normal" (float x 3, Potree's own name for normals),
// and our extras, which Potree reads as unknown scalars (their first element) and otherwise ignores:
// "sffd_axis_u", "sffd_axis_v" (float x 3, the splat's tangent axes scaled by its radii), "sffd_lod_radius"
// (float: the radius that covers every splat this point stands for when its node is drawn without its
// children), "sffd_uv" (float x 2) and "sffd_uv_axes" (float x 4) when the cloud is textured. The texture
// itself cannot go into metadata.json or a point attribute: it is DIR/texture.png, named by "sffd".
//
// One validation on open, before any point is read, every refusal "path: problem" naming the file:
//   metadata.json: a regular file of at most kMaxPotreeMetaBytes, JSON nesting within kMaxJsonDepth;
//   version 2.x; encoding "DEFAULT" (BROTLI is refused by name); points a whole number of at most
//   kMaxPotreePoints; offset, scale (each > 0), boundingBox (min < max, a cube as Potree's halving assumes
//   nothing else), spacing finite; at most kMaxPotreeAttributes attributes, each a known type with
//   elementSize its type's size, size = numElements · elementSize, at most kMaxPotreePointBytes a point;
//   "position" present as int32 x 3; firstChunkSize a positive multiple of 22; stepSize 1..kMaxPotreeDepth.
//   hierarchy.bin and octree.bin are the fixed names beside metadata.json, and the texture a plain name,
//   all resolved inside DIR (resolve_resource: no absolute path, no "..", no symlink out).
//   hierarchy.bin (at most kMaxPotreeHierarchyBytes): every chunk inside the file on a record boundary, no
//   record read twice (chunks may not overlap or loop), a chunk's records exactly the nodes its masks
//   declare, at most kMaxPotreeNodes nodes, depth at most kMaxPotreeDepth, types 0..2 with a leaf
//   declaring no children. Nodes: byteOffset + byteSize inside octree.bin, byteSize = numPoints · the
//   point size (the ratio budget: no node claims points it has no bytes for), no two nodes' bytes
//   overlapping, and the nodes' points adding up to "points". A node with byteSize 0 has 0 points
//   whatever it declares: some PotreeConverter versions write empty nodes with a non-zero count, and
//   Potree's loader reads them as empty too.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::assets {

inline constexpr std::uint64_t kMaxPotreeMetaBytes = std::uint64_t(16) << 20;
inline constexpr std::uint64_t kMaxPotreeHierarchyBytes = std::uint64_t(512) << 20;
inline constexpr std::uint64_t kMaxPotreePoints = std::uint64_t(1) << 31;
inline constexpr std::size_t kMaxPotreeNodes = std::size_t(1) << 24;
inline constexpr std::size_t kMaxPotreeAttributes = 64;
inline constexpr std::uint64_t kMaxPotreePointBytes = 1024;
inline constexpr int kMaxPotreeDepth = 24;
inline constexpr std::size_t kPotreeNodeBytes = 22;

enum class PotreeType { int8, uint8, int16, uint16, int32, uint32, int64, uint64, float32, float64 };

struct PotreeAttribute {
    std::string name;
    PotreeType type = PotreeType::float32;
    int elements = 1;
    std::uint32_t bytes = 0;   // numElements · elementSize
    std::uint32_t offset = 0;  // within a point
};

struct PotreeNode {
    std::string name;  // "r", "r0", "r07", ...: the child indices from the root
    int level = 0;
    glm::dvec3 lo{0.0}, hi{0.0};  // its cube
    std::int32_t parent = -1;
    std::array<std::int32_t, 8> children{-1, -1, -1, -1, -1, -1, -1, -1};
    std::uint32_t points = 0;
    std::uint64_t byte_offset = 0, byte_size = 0;  // in octree.bin
    bool has_children() const;
};

struct PotreeOctree {
    std::filesystem::path path;  // metadata.json
    std::filesystem::path hierarchy_path, octree_path;
    std::optional<std::filesystem::path> texture_path;
    std::string version, name;
    std::uint64_t points = 0;
    int step_size = 0, depth = 0;
    std::uint64_t first_chunk_size = 0, hierarchy_bytes = 0, octree_bytes = 0;
    std::uint32_t chunks = 0;  // hierarchy chunks read
    glm::dvec3 offset{0.0}, scale{1.0}, lo{0.0}, hi{0.0};
    double spacing = 0.0;
    bool has_origin = false;  // "sffd" recorded the cloud's origin
    glm::dvec3 origin{0.0};
    std::vector<PotreeAttribute> attributes;
    std::uint32_t point_bytes = 0;
    std::vector<PotreeNode> nodes;  // the root at 0; parents before children (breadth first per chunk)
    const PotreeAttribute* attribute(const std::string& name) const;
};

// Reads metadata.json and the whole hierarchy and validates them (above); octree.bin is only sized.
Result<PotreeOctree> open_potree2(const std::filesystem::path& metadata);

// The points of a set of nodes (a cut through the hierarchy), node after node in the order given, as one
// cloud. A point of a node whose existing children are not all in the set stands for them: its axes are
// grown to its sffd_lod_radius (each axis at least that long, so its ellipse holds the radius's disc).
// Attributes we do not write are skipped; a file without normals or splat axes (PotreeConverter's own)
// is refused here (read_potree2_geometry estimates them). Refused when the set holds more than
// kMaxPotreePoints points or names a node twice.
Result<SplatCloud> read_potree2_nodes(const PotreeOctree& octree, const std::vector<std::uint32_t>& nodes);
// One node (its points grown when it has children).
Result<SplatCloud> read_potree2_node(const PotreeOctree& octree, std::uint32_t node);
// One node's points at their own radii, with each point's sffd_lod_radius (0 without the attribute), and
// without the texture: what a streaming loader holds, growing the axes itself when it draws the node
// without all of its children (grow_to_lod_radius, the rule read_potree2_nodes applies).
struct PotreeNodePoints {
    SplatCloud cloud;
    std::vector<float> lod_radius;
};
Result<PotreeNodePoints> read_potree2_node_points(const PotreeOctree& octree, std::uint32_t node);
// Splats first .. first + lod_radius.size() of `cloud`: each axis at least its lod radius long.
void grow_to_lod_radius(SplatCloud& cloud, std::size_t first, const std::vector<float>& lod_radius);
// The full finest detail: every node, every splat at its own radius.
Result<SplatCloud> read_potree2(const PotreeOctree& octree);
// The nodes of the cut that stops at `level` (every node of at most that level), breadth first.
std::vector<std::uint32_t> potree2_level_cut(const PotreeOctree& octree, int level);

// A human-readable summary (points, nodes, depth, chunks, attributes, bounds), one fact a line.
std::string describe(const PotreeOctree& octree);

}  // namespace sffd::assets
