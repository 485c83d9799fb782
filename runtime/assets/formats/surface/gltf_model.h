// A loaded glTF document (load_gltf_model(), gltf_io.h): tinygltf's model, and where its buffers' bytes
// lie. A well-formed GLB's BIN chunk is read where the file is mapped, never copied: copying it was half
// the fresh memory a large GLB's first open faulted in. Buffer 0 is then a one-byte stand-in in `gltf`,
// its bytes are `bin`, and `file` keeps them mapped for as long as the model lives. Read every buffer
// through gltf_buffer(), and ask gltf_changed() once what was read from it is decoded.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <string_view>

#include <glm/glm.hpp>
#include <tiny_gltf.h>

#include "runtime/assets/formats/archive/mapped_file.h"

namespace sffd::assets {

struct GltfModel {
    tinygltf::Model gltf;
    std::shared_ptr<const MappedFile> file;  // the mapping `bin` lies in; null when nothing was left there
    std::string_view bin;                    // buffer 0's bytes when they stayed in the mapping
};

// Buffer `index`'s bytes; empty for an index out of range.
inline std::span<const unsigned char> gltf_buffer(const GltfModel& m, std::size_t index) {
    if (index == 0 && m.file) return {reinterpret_cast<const unsigned char*>(m.bin.data()), m.bin.size()};
    if (index >= m.gltf.buffers.size()) return {};
    return m.gltf.buffers[index].data;
}

// The mapped file was shortened while it was read (MappedFile::changed()): bytes read from `bin` may have
// been zeros instead of the file's.
inline bool gltf_changed(const GltfModel& m) { return m.file && m.file->changed(); }

// A node's local matrix: `matrix` when it has 16 numbers, else T * R * S, the rotation normalised (a zero
// quaternion reads as none). Every glTF reader places its nodes with this one definition.
glm::dmat4 gltf_node_matrix(const tinygltf::Node& node);

}  // namespace sffd::assets
