#include "runtime/assets/formats/lod/streamed_sog.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <set>

#include <nlohmann/json.hpp>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/json_fields.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/core/file_io.h"

namespace sffd::lod {
namespace fs = std::filesystem;

namespace {

using json = nlohmann::json;

using assets::json_fields::member;
using assets::json_fields::vec3;
using assets::json_fields::whole;

// A unit or environment name: relative, '/'-separated, naming a SOG folder's meta.json or a .sog.
bool plain_relative(const std::string& name) {
    if (name.empty() || name.front() == '/' || name.find('\\') != std::string::npos ||
        name.find('\0') != std::string::npos)
        return false;
    const fs::path p(name);
    for (const auto& part : p)
        if (part == ".." || part == ".") return false;
    return p.filename() == "meta.json" || p.extension() == ".sog";
}

class Parser {
public:
    explicit Parser(StreamedSog& s) : s_(s), name_(s.path.string()) {}

    Status parse(const json& m) {
        if (!m.is_object()) return fail("lod-meta.json is not a JSON object");
        const json& version = member(m, "version");
        if (!version.is_null()) {
            std::uint64_t v = 0;
            if (!whole(version, v) || v != 1)
                return fail("streamed SOG version " + version.dump() + " is not read (version 1 is)");
            s_.version = 1;
        }
        if (const json& g = member(member(m, "asset"), "generator"); g.is_string()) s_.generator = g;
        std::uint64_t levels = 0;
        if (!whole(member(m, "lodLevels"), levels) || levels < 1 || levels > std::uint64_t(kMaxLodLevels))
            return fail("\"lodLevels\" must be a whole number from 1 to " + std::to_string(kMaxLodLevels));
        s_.levels = int(levels);
        const json& counts = member(m, "counts");
        if (!counts.is_null()) {
            if (!counts.is_array() || counts.size() != levels)
                return fail("\"counts\" must list one count per level (" + std::to_string(levels) + ")");
            for (const json& c : counts) {
                std::uint64_t v = 0;
                if (!whole(c, v)) return fail("\"counts\": " + c.dump() + " is not a whole number");
                declared_.push_back(v);
            }
            const json& count = member(m, "count");
            std::uint64_t total = 0, sum = 0;
            for (const std::uint64_t v : declared_) sum += v;  // each below 2^53, at most 32 of them
            if (!count.is_null() && (!whole(count, total) || total != sum))
                return fail("\"count\" " + count.dump() + " is not the sum of \"counts\" (" +
                            std::to_string(sum) + ")");
        }
        const json& files = member(m, "filenames");
        if (!files.is_array()) return fail("\"filenames\" is missing or not a list");
        if (files.size() > kMaxLodFiles)
            return fail(std::to_string(files.size()) + " filenames, more than the " +
                        std::to_string(kMaxLodFiles) + " limit");
        std::set<std::string> seen;
        for (const json& f : files) {
            if (!f.is_string() || !plain_relative(f.get<std::string>()))
                return fail("\"filenames\": " + f.dump() +
                            " is not a relative path to a SOG folder's meta.json or a .sog file");
            if (!seen.insert(f.get<std::string>()).second)
                return fail("\"filenames\": " + f.dump() + " is listed twice");
            LodUnit u;
            u.name = f.get<std::string>();
            s_.units.push_back(std::move(u));
        }
        if (const json& env = member(m, "environment"); !env.is_null()) {
            if (!env.is_string() || !plain_relative(env.get<std::string>()))
                return fail("\"environment\": " + env.dump() +
                            " is not a relative path to a SOG folder's meta.json or a .sog file");
            auto p = resolve_resource(s_.path, env.get<std::string>());
            if (!p) return make_error(p.message());
            s_.environment = *p;
        }
        const json& tree = member(m, "tree");
        if (!tree.is_object()) return fail("\"tree\" is missing or not an object");
        if (Status st = node(tree, -1, "tree"); !st) return st;
        return units();
    }

private:
    Status fail(const std::string& why) const { return make_error(name_ + ": " + why); }

    Status node(const json& j, std::int32_t parent, const std::string& where) {
        if (!j.is_object()) return fail(where + " is not an object");
        if (s_.nodes.size() >= kMaxLodNodes)
            return fail("more than " + std::to_string(kMaxLodNodes) + " tree nodes");
        const std::uint32_t self = std::uint32_t(s_.nodes.size());
        s_.nodes.emplace_back();
        s_.nodes[self].parent = parent;
        LodNode n;
        n.parent = parent;
        const json& bound = member(j, "bound");
        if (!vec3(member(bound, "min"), n.lo) || !vec3(member(bound, "max"), n.hi))
            return fail(where + ".bound: min and max must be 3 finite numbers each");
        if (n.lo.x > n.hi.x || n.lo.y > n.hi.y || n.lo.z > n.hi.z)
            return fail(where + ".bound: min is above max");
        n.lods.resize(std::size_t(s_.levels));
        const json& lods = member(j, "lods");
        if (!lods.is_null()) {
            if (!lods.is_object()) return fail(where + ".lods is not an object");
            for (const auto& [key, ref] : lods.items()) {
                const std::string at = where + ".lods[\"" + key + "\"]";
                char* end = nullptr;
                const long level = std::strtol(key.c_str(), &end, 10);
                if (key.empty() || *end != '\0' || level < 0 || level >= s_.levels ||
                    std::to_string(level) != key)
                    return fail(at + ": not a level below lodLevels (" + std::to_string(s_.levels) + ")");
                LodRun r;
                std::uint64_t file = 0;
                if (!whole(member(ref, "file"), file) || file >= s_.units.size())
                    return fail(at + ".file: not an index into \"filenames\" (" +
                                std::to_string(s_.units.size()) + " listed)");
                r.file = std::uint32_t(file);
                if (!whole(member(ref, "offset"), r.offset) || !whole(member(ref, "count"), r.count))
                    return fail(at + ": offset and count must be whole numbers");
                LodUnit& u = s_.units[file];
                if (u.level >= 0 && u.level != int(level))
                    return fail(at + ": file \"" + u.name + "\" holds level " + std::to_string(u.level) +
                                ", not " + key);
                u.level = int(level);
                n.lods[std::size_t(level)] = r;
            }
        }
        const json& children = member(j, "children");
        if (!children.is_null() && !children.is_array()) return fail(where + ".children is not a list");
        s_.nodes[self].lo = n.lo, s_.nodes[self].hi = n.hi, s_.nodes[self].lods = std::move(n.lods);
        if (children.is_array()) {
            for (std::size_t c = 0; c < children.size(); ++c) {
                s_.nodes[self].children.push_back(std::uint32_t(s_.nodes.size()));
                if (Status st =
                        node(children[c], std::int32_t(self), where + ".children[" + std::to_string(c) + "]");
                    !st)
                    return st;
            }
        }
        return {};
    }

    // Each unit's meta.json and images, then the runs against the units' counts.
    Status units() {
        for (LodUnit& u : s_.units) {
            auto p = resolve_resource(s_.path, u.name);
            if (!p) return make_error(p.message());
            u.path = *p;
            std::error_code ec;
            if (u.path.extension() == ".sog") {
                // An archive: its count is checked when it is decoded (read_unit), its size here.
                u.parts.push_back({u.path, fs::file_size(u.path, ec)});
                u.count = gaussian::kMaxGaussians + 1;  // unknown until decoded
                continue;
            }
            auto text = read_file(u.path, kMaxUnitMetaBytes);
            if (!text) return make_error(text.message());
            const std::string un = u.path.string();
            if (auto d = check_json_depth(*text, un); !d) return d;
            const json m = json::parse(*text, nullptr, false);
            if (m.is_discarded() || !m.is_object()) return make_error(un + ": not a JSON object");
            if (!whole(member(m, "count"), u.count))
                return make_error(un + ": \"count\" is missing or not a whole number");
            if (u.count > gaussian::kMaxGaussians)
                return make_error(un + ": declares " + std::to_string(u.count) +
                                  " Gaussians, more than the " + std::to_string(gaussian::kMaxGaussians) +
                                  " limit");
            u.parts.push_back({u.path, text->size()});
            std::uint64_t image_bytes = 0;
            for (const char* sec : {"means", "scales", "quats", "sh0", "shN"}) {
                const json& files = member(member(m, sec), "files");
                if (!files.is_array()) {
                    if (std::string(sec) == "shN") continue;
                    return make_error(un + ": \"" + sec + ".files\" is missing");
                }
                for (const json& f : files) {
                    if (!f.is_string() || f.get<std::string>().empty() ||
                        f.get<std::string>().find_first_of("/\\") != std::string::npos ||
                        f.get<std::string>() == "." || f.get<std::string>() == "..")
                        return make_error(un + ": " + sec + ".files: " + f.dump() +
                                          " is not a plain file name");
                    const fs::path img = u.path.parent_path() / f.get<std::string>();
                    if (!fs::is_regular_file(img, ec))
                        return make_error(img.string() + ": " +
                                          (fs::exists(img, ec) ? "not a regular file" : "no such file"));
                    // Confined like the units: an image that is a symlink must stay inside the folder.
                    const std::string rel = (fs::path(u.name).parent_path() / f.get<std::string>()).string();
                    if (auto inside = resolve_resource(s_.path, rel); !inside)
                        return make_error(inside.message());
                    const std::uint64_t b = fs::file_size(img, ec);
                    image_bytes += b;
                    u.parts.push_back({img, b});
                }
            }
            if (u.count > kMaxTexelsPerByte * std::max<std::uint64_t>(image_bytes, 1))
                return make_error(un + ": " + std::to_string(u.count) + " Gaussians in " +
                                  std::to_string(image_bytes) + " bytes of images, more than " +
                                  std::to_string(kMaxTexelsPerByte) + " a byte");
        }
        // Runs per unit: sorted by offset they must tile [0, count).
        std::vector<std::vector<std::pair<std::uint64_t, std::uint64_t>>> runs(s_.units.size());
        s_.counts.assign(std::size_t(s_.levels), 0);
        for (const LodNode& n : s_.nodes)
            for (std::size_t l = 0; l < n.lods.size(); ++l)
                if (n.lods[l]) {
                    runs[n.lods[l]->file].push_back({n.lods[l]->offset, n.lods[l]->count});
                    s_.counts[l] += n.lods[l]->count;  // each count below 2^53, at most 2^24 nodes: no wrap
                }
        for (std::size_t f = 0; f < s_.units.size(); ++f) {
            LodUnit& u = s_.units[f];
            auto& r = runs[f];
            std::sort(r.begin(), r.end());
            std::uint64_t at = 0;
            for (const auto& [offset, count] : r) {
                if (offset != at)
                    return fail("\"" + u.name +
                                "\": " + (offset < at ? "runs overlap at offset " : "a gap before offset ") +
                                std::to_string(offset));
                at = offset + count;
                if (u.path.extension() != ".sog" && at > u.count)
                    return fail("\"" + u.name + "\": a run ends at " + std::to_string(at) +
                                ", past the unit's " + std::to_string(u.count) + " Gaussians");
            }
            if (u.path.extension() == ".sog") u.count = at;  // checked on decoding
            if (at != u.count)
                return fail("\"" + u.name + "\": the runs cover " + std::to_string(at) + " of its " +
                            std::to_string(u.count) + " Gaussians");
        }
        if (!declared_.empty())
            for (int l = 0; l < s_.levels; ++l)
                if (declared_[std::size_t(l)] != s_.counts[std::size_t(l)])
                    return fail("level " + std::to_string(l) + ": \"counts\" says " +
                                std::to_string(declared_[std::size_t(l)]) + ", the tree holds " +
                                std::to_string(s_.counts[std::size_t(l)]));
        return {};
    }

    StreamedSog& s_;
    std::string name_;
    std::vector<std::uint64_t> declared_;
};

}  // namespace

std::uint64_t StreamedSog::total() const {
    return std::accumulate(counts.begin(), counts.end(), std::uint64_t(0));
}

Result<StreamedSog> open_streamed_sog(const fs::path& lod_meta) {
    StreamedSog s;
    s.path = lod_meta;
    auto text = read_file(lod_meta, kMaxLodMetaBytes);
    if (!text) return make_error(text.message());
    if (auto d = check_json_depth(*text, lod_meta.string()); !d) return make_error(d.message());
    const json m = json::parse(*text, nullptr, false);
    if (m.is_discarded()) return make_error(lod_meta.string() + ": not valid JSON");
    if (Status st = Parser(s).parse(m); !st) return make_error(st.message());
    return s;
}

std::vector<LodPart> node_parts(const StreamedSog& s, std::uint32_t node, int level) {
    if (node >= s.nodes.size() || level < 0 || level >= s.levels) return {};
    const auto& run = s.nodes[node].lods[std::size_t(level)];
    if (!run) return {};
    return s.units[run->file].parts;
}

Result<GaussianCloud> read_unit(const StreamedSog& s, std::uint32_t unit) {
    if (unit >= s.units.size()) return make_error(s.path.string() + ": no unit " + std::to_string(unit));
    const LodUnit& u = s.units[unit];
    auto g = gaussian::read_sog(u.path);
    if (!g) return make_error(g.message());
    if (g->size() != u.count)
        return make_error(u.path.string() + ": holds " + std::to_string(g->size()) + " Gaussians, " +
                          s.path.string() + " places " + std::to_string(u.count) + " in it");
    if (Status st = gaussian::validate(*g, u.path.string()); !st) return make_error(st.message());
    return g;
}

GaussianCloud slice(const GaussianCloud& unit, const LodRun& run) {
    GaussianCloud out;
    out.origin = unit.origin;
    out.sh_degree = unit.sh_degree;
    const std::size_t a = std::size_t(run.offset), b = std::size_t(run.offset + run.count);
    const std::size_t K3 = std::size_t(sh_coeffs(unit.sh_degree)) * 3;
    out.positions.assign(unit.positions.begin() + long(a), unit.positions.begin() + long(b));
    out.scales.assign(unit.scales.begin() + long(a), unit.scales.begin() + long(b));
    out.rotations.assign(unit.rotations.begin() + long(a), unit.rotations.begin() + long(b));
    out.opacities.assign(unit.opacities.begin() + long(a), unit.opacities.begin() + long(b));
    out.sh.assign(unit.sh.begin() + long(a * K3), unit.sh.begin() + long(b * K3));
    return out;
}

Result<GaussianCloud> read_level(const StreamedSog& s, int level) {
    if (level < 0 || level >= s.levels)
        return make_error(s.path.string() + ": no level " + std::to_string(level) + " (" +
                          std::to_string(s.levels) + " levels)");
    if (s.counts[std::size_t(level)] > gaussian::kMaxGaussians)
        return make_error(s.path.string() + ": level " + std::to_string(level) + " holds " +
                          std::to_string(s.counts[std::size_t(level)]) + " Gaussians, more than the " +
                          std::to_string(gaussian::kMaxGaussians) + " limit of one cloud");
    GaussianCloud out;
    bool first = true;
    // Units in the order the tree first uses them; each decoded once, kept until its last run is cut.
    std::map<std::uint32_t, std::size_t> remaining;
    for (const LodNode& n : s.nodes)
        if (n.lods[std::size_t(level)]) ++remaining[n.lods[std::size_t(level)]->file];
    std::map<std::uint32_t, GaussianCloud> open;
    for (const LodNode& n : s.nodes) {
        const auto& run = n.lods[std::size_t(level)];
        if (!run) continue;
        auto it = open.find(run->file);
        if (it == open.end()) {
            auto g = read_unit(s, run->file);
            if (!g) return g.error();
            it = open.emplace(run->file, std::move(*g)).first;
        }
        const GaussianCloud& u = it->second;
        if (first) out.sh_degree = u.sh_degree, out.origin = u.origin, first = false;
        if (u.sh_degree != out.sh_degree)
            return make_error(s.units[run->file].path.string() + ": SH degree " +
                              std::to_string(u.sh_degree) + ", the level's other units have " +
                              std::to_string(out.sh_degree));
        const GaussianCloud part = slice(u, *run);
        const glm::dvec3 shift = part.origin - out.origin;
        for (const glm::vec3& p : part.positions) out.positions.push_back(glm::vec3(glm::dvec3(p) + shift));
        out.scales.insert(out.scales.end(), part.scales.begin(), part.scales.end());
        out.rotations.insert(out.rotations.end(), part.rotations.begin(), part.rotations.end());
        out.opacities.insert(out.opacities.end(), part.opacities.begin(), part.opacities.end());
        out.sh.insert(out.sh.end(), part.sh.begin(), part.sh.end());
        if (--remaining[run->file] == 0) open.erase(run->file);
    }
    return out;
}

std::string describe(const StreamedSog& s) {
    std::string t;
    char line[512];
    std::snprintf(line, sizeof line, "streamed SOG (lod-meta.json version %d%s%s)\n", s.version,
                  s.generator.empty() ? "" : ", written by ", s.generator.c_str());
    t += line;
    std::snprintf(line, sizeof line, "levels: %d (0 = full detail)\n", s.levels);
    t += line;
    std::vector<std::size_t> units(std::size_t(s.levels), 0);
    std::uint64_t bytes = 0;
    for (const LodUnit& u : s.units) {
        if (u.level >= 0) ++units[std::size_t(u.level)];
        for (const LodPart& p : u.parts) bytes += p.bytes;
    }
    for (int l = 0; l < s.levels; ++l) {
        std::snprintf(line, sizeof line, "  level %d: %llu Gaussians in %zu units\n", l,
                      static_cast<unsigned long long>(s.counts[std::size_t(l)]), units[std::size_t(l)]);
        t += line;
    }
    std::size_t leaves = 0, depth = 0;
    std::vector<std::size_t> d(s.nodes.size(), 0);
    for (std::size_t i = 0; i < s.nodes.size(); ++i) {
        if (s.nodes[i].parent >= 0) d[i] = d[std::size_t(s.nodes[i].parent)] + 1;
        depth = std::max(depth, d[i]);
        if (s.nodes[i].children.empty()) ++leaves;
    }
    std::snprintf(line, sizeof line, "total: %llu Gaussians, %zu units, %.1f MB\n",
                  static_cast<unsigned long long>(s.total()), s.units.size(), double(bytes) / 1e6);
    t += line;
    std::snprintf(line, sizeof line, "tree: %zu nodes, %zu leaves, depth %zu\n", s.nodes.size(), leaves,
                  depth);
    t += line;
    if (!s.nodes.empty()) {
        const LodNode& r = s.nodes[0];
        std::snprintf(line, sizeof line, "bounds: [%.6g, %.6g, %.6g] .. [%.6g, %.6g, %.6g]\n", r.lo.x, r.lo.y,
                      r.lo.z, r.hi.x, r.hi.y, r.hi.z);
        t += line;
    }
    if (s.environment) t += "environment: " + s.environment->string() + "\n";
    return t;
}

}  // namespace sffd::lod
