#include "runtime/assets/formats/surface/gltf_point_columns.h"

#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/formats/surface/gltf_model.h"

namespace sffd::assets {
using nlohmann::json;

namespace {

constexpr std::uint8_t kSavedBits = kPointSelected | kPointHidden;

int add_view(json& views, std::string& bin, const void* data, std::size_t bytes, int stride) {
    while (bin.size() % 4) bin.push_back('\0');
    json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}, {"target", 34962}};
    if (stride) v["byteStride"] = stride;
    bin.append(static_cast<const char*>(data), bytes);
    views.push_back(v);
    return int(views.size()) - 1;
}

}  // namespace

Status append_point_columns(json& accessors, json& views, std::string& bin, json& attributes, std::size_t n,
                            const PointFlags* flags, const PointWeights* weights, const std::string& what) {
    if (flags && !flags->bits.empty()) {
        if (flags->bits.size() != n)
            return make_error(what + ": flags hold " + std::to_string(flags->bits.size()) + " values for " +
                              std::to_string(n) + " points");
        bool any = false;
        for (std::uint8_t b : flags->bits) any = any || (b & kSavedBits) != 0;
        if (any) {
            std::vector<std::uint8_t> padded(n * 4, 0);  // one byte a point, 4 bytes apart
            for (std::size_t i = 0; i < n; ++i) padded[4 * i] = flags->bits[i] & kSavedBits;
            const int v = add_view(views, bin, padded.data(), padded.size(), 4);
            accessors.push_back(
                {{"bufferView", v}, {"componentType", 5121}, {"count", n}, {"type", "SCALAR"}});
            attributes["_FLAGS"] = int(accessors.size()) - 1;
        }
    }
    if (weights && !weights->values.empty()) {
        if (weights->values.size() != n)
            return make_error(what + ": weights hold " + std::to_string(weights->values.size()) +
                              " values for " + std::to_string(n) + " points");
        for (std::size_t i = 0; i < n; ++i)
            if (!(weights->values[i] >= 0.0f && weights->values[i] <= 1.0f))
                return make_error(what + ": weight " + std::to_string(weights->values[i]) + " of point " +
                                  std::to_string(i) + " is outside [0, 1]");
        const int v = add_view(views, bin, weights->values.data(), n * 4, 0);
        accessors.push_back({{"bufferView", v}, {"componentType", 5126}, {"count", n}, {"type", "SCALAR"}});
        attributes["_WEIGHT"] = int(accessors.size()) - 1;
    }
    return {};
}

Status read_point_columns(const GltfModel& model, const std::map<std::string, int>& attributes, std::size_t n,
                          const std::string& what, PointFlags& flags, PointWeights& weights) {
    flags.bits.clear(), weights.values.clear();
    if (auto it = attributes.find("_FLAGS"); it != attributes.end()) {
        auto v = read_gltf_accessor(model, it->second, 1, what, "_FLAGS");
        if (!v) return v.error();
        if (v->size() != n)
            return make_error(what + ": _FLAGS has " + std::to_string(v->size()) + " values for " +
                              std::to_string(n) + " points");
        flags.bits.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const double x = (*v)[i];
            if (!(x >= 0.0 && x <= 255.0) || x != std::floor(x) ||
                (std::uint32_t(x) & ~std::uint32_t(kSavedBits)))
                return make_error(what + ": _FLAGS value " + std::to_string(x) + " of point " +
                                  std::to_string(i) +
                                  ": only the selected (1) and hidden (2) bits are stored");
            flags.bits[i] = std::uint8_t(x);
        }
    }
    if (auto it = attributes.find("_WEIGHT"); it != attributes.end()) {
        auto v = read_gltf_accessor(model, it->second, 1, what, "_WEIGHT");
        if (!v) return v.error();
        if (v->size() != n)
            return make_error(what + ": _WEIGHT has " + std::to_string(v->size()) + " values for " +
                              std::to_string(n) + " points");
        weights.values.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const double x = (*v)[i];
            if (!(x >= 0.0 && x <= 1.0))
                return make_error(what + ": _WEIGHT " + std::to_string(x) + " of point " + std::to_string(i) +
                                  " is outside [0, 1]");
            weights.values[i] = float(x);
        }
    }
    return {};
}

}  // namespace sffd::assets
