#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "runtime/assets/formats/json_fields.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/assets/formats/surface/potree2_detail.h"
#include "runtime/assets/import.h"
#include "runtime/assets/import_detail.h"
#include "runtime/core/file_io.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using namespace potree2_detail;

bool PotreeNode::has_children() const {
    return std::any_of(children.begin(), children.end(), [](std::int32_t c) { return c >= 0; });
}

const PotreeAttribute* PotreeOctree::attribute(const std::string& n) const {
    for (const PotreeAttribute& a : attributes)
        if (a.name == n) return &a;
    return nullptr;
}

namespace {

using json = nlohmann::json;

using assets::json_fields::member;
using assets::json_fields::vec3;
using assets::json_fields::whole;

class Parser {
public:
    explicit Parser(PotreeOctree& o) : o_(o), name_(o.path.string()) {}

    Status fail(const std::string& why) const { return make_error(name_ + ": " + why); }

    Status metadata(const json& m) {
        if (!m.is_object()) return fail("metadata.json is not a JSON object");
        const json& version = member(m, "version");
        if (!version.is_string() || version.get<std::string>().rfind("2.", 0) != 0)
            return fail("Potree version " + version.dump() + " is not read (version 2.x is)");
        o_.version = version.get<std::string>();
        if (const json& n = member(m, "name"); n.is_string()) o_.name = n.get<std::string>();
        const json& enc = member(m, "encoding");
        if (!enc.is_null() && (!enc.is_string() || enc.get<std::string>() != "DEFAULT"))
            return fail("encoding " + enc.dump() +
                        " is not read (DEFAULT is; BROTLI needs Potree's decoder)");
        if (!whole(member(m, "points"), o_.points) || o_.points > kMaxPotreePoints)
            return fail("\"points\" must be a whole number of at most " + std::to_string(kMaxPotreePoints));
        if (!vec3(member(m, "offset"), o_.offset)) return fail("\"offset\" must be 3 finite numbers");
        if (!vec3(member(m, "scale"), o_.scale) || !(o_.scale.x > 0 && o_.scale.y > 0 && o_.scale.z > 0))
            return fail("\"scale\" must be 3 finite numbers above 0");
        const json& box = member(m, "boundingBox");
        if (!vec3(member(box, "min"), o_.lo) || !vec3(member(box, "max"), o_.hi))
            return fail("\"boundingBox\": min and max must be 3 finite numbers each");
        if (!(o_.lo.x < o_.hi.x && o_.lo.y < o_.hi.y && o_.lo.z < o_.hi.z))
            return fail("\"boundingBox\": min is not below max");
        if (const json& s = member(m, "spacing"); s.is_number()) o_.spacing = s.get<double>();
        if (!std::isfinite(o_.spacing)) return fail("\"spacing\" is not a finite number");
        const json& h = member(m, "hierarchy");
        std::uint64_t v = 0;
        if (!whole(member(h, "firstChunkSize"), o_.first_chunk_size) || o_.first_chunk_size == 0 ||
            o_.first_chunk_size % kPotreeNodeBytes != 0)
            return fail(
                "\"hierarchy.firstChunkSize\" must be a positive multiple of 22 (bytes of whole nodes)");
        if (!whole(member(h, "stepSize"), v) || v < 1 || v > std::uint64_t(kMaxPotreeDepth))
            return fail("\"hierarchy.stepSize\" must be a whole number from 1 to " +
                        std::to_string(kMaxPotreeDepth));
        o_.step_size = int(v);
        if (const json& d = member(h, "depth");
            !d.is_null() && (!whole(d, v) || v > std::uint64_t(kMaxPotreeDepth)))
            return fail("\"hierarchy.depth\" must be a whole number of at most " +
                        std::to_string(kMaxPotreeDepth));
        if (Status s = attributes(member(m, "attributes")); !s) return s;
        const json& sffd = member(m, "sffd");
        if (!sffd.is_null()) {
            if (!sffd.is_object()) return fail("\"sffd\" is not an object");
            if (const json& org = member(sffd, "origin"); !org.is_null()) {
                if (!vec3(org, o_.origin)) return fail("\"sffd.origin\" must be 3 finite numbers");
                o_.has_origin = true;
            }
            if (const json& t = member(sffd, "texture"); !t.is_null()) {
                if (!t.is_string()) return fail("\"sffd.texture\" is not a file name");
                auto p = resolve_resource(o_.path, t.get<std::string>());
                if (!p) return make_error(p.message());
                o_.texture_path = *p;
            }
        }
        return {};
    }

    Status attributes(const json& list) {
        if (!list.is_array() || list.empty()) return fail("\"attributes\" is missing or empty");
        if (list.size() > kMaxPotreeAttributes)
            return fail(std::to_string(list.size()) + " attributes, more than the " +
                        std::to_string(kMaxPotreeAttributes) + " limit");
        std::set<std::string> seen;
        std::uint64_t at = 0;
        for (std::size_t i = 0; i < list.size(); ++i) {
            const json& j = list[i];
            const std::string where = "attributes[" + std::to_string(i) + "]";
            PotreeAttribute a;
            const json& n = member(j, "name");
            if (!n.is_string()) return fail(where + ": no name");
            a.name = n.get<std::string>();
            if (!seen.insert(a.name).second) return fail(where + ": '" + a.name + "' is listed twice");
            const json& t = member(j, "type");
            if (!t.is_string() || !parse_type(t.get<std::string>(), a.type))
                return fail(where + " '" + a.name + "': type " + t.dump() + " is not one of Potree's");
            std::uint64_t elements = 0, element_size = 0, size = 0;
            if (!whole(member(j, "numElements"), elements) || elements < 1 || elements > 16)
                return fail(where + " '" + a.name + "': numElements must be 1 to 16");
            if (!whole(member(j, "elementSize"), element_size) || element_size != type_bytes(a.type))
                return fail(where + " '" + a.name + "': elementSize must be " +
                            std::to_string(type_bytes(a.type)) + " for " + type_name(a.type));
            if (!whole(member(j, "size"), size) || size != elements * element_size)
                return fail(where + " '" + a.name + "': size must be numElements x elementSize (" +
                            std::to_string(elements * element_size) + ")");
            a.elements = int(elements);
            a.bytes = std::uint32_t(size);
            a.offset = std::uint32_t(at);
            at += size;
            if (at > kMaxPotreePointBytes)
                return fail("a point of more than " + std::to_string(kMaxPotreePointBytes) + " bytes");
            for (const AttributeSpec* s :
                 {&kPosition, &kRgb, &kAlpha, &kNormal, &kAxisU, &kAxisV, &kLodRadius, &kUv, &kUvAxes})
                if (a.name == s->name && (a.type != s->type || a.elements != s->elements))
                    return fail(where + " '" + a.name + "' is " + type_name(a.type) + " x " +
                                std::to_string(a.elements) + "; it is read as " + type_name(s->type) + " x " +
                                std::to_string(s->elements));
            o_.attributes.push_back(a);
        }
        o_.point_bytes = std::uint32_t(at);
        if (!o_.attribute(kPosition.name)) return fail("no \"position\" attribute (int32 x 3)");
        return {};
    }

    // Every chunk from the root's, as Potree's parseHierarchy walks them.
    Status hierarchy(const std::string& bytes) {
        const std::string hname = o_.hierarchy_path.string();
        const std::uint64_t records = bytes.size() / kPotreeNodeBytes;
        if (bytes.size() % kPotreeNodeBytes != 0)
            return make_error(hname + ": " + std::to_string(bytes.size()) +
                              " bytes, not whole 22-byte nodes");
        std::vector<bool> used(std::size_t(records), false);
        PotreeNode root;
        root.name = "r", root.lo = o_.lo, root.hi = o_.hi;
        o_.nodes.push_back(root);
        struct Pending {
            std::uint32_t node;
            std::uint64_t offset, size;
        };
        std::deque<Pending> todo{{0, 0, o_.first_chunk_size}};
        while (!todo.empty()) {
            const Pending p = todo.front();
            todo.pop_front();
            const std::string chunk =
                "chunk at byte " + std::to_string(p.offset) + " (node " + o_.nodes[p.node].name + ")";
            if (p.size == 0 || p.offset % kPotreeNodeBytes != 0 || p.size % kPotreeNodeBytes != 0 ||
                p.offset > bytes.size() || p.size > bytes.size() - p.offset)
                return make_error(hname + ": " + chunk + " of " + std::to_string(p.size) +
                                  " bytes is not whole nodes inside the file (" +
                                  std::to_string(bytes.size()) + " bytes)");
            ++o_.chunks;
            const std::size_t first = std::size_t(p.offset / kPotreeNodeBytes),
                              n = std::size_t(p.size / kPotreeNodeBytes);
            std::vector<std::uint32_t> order{p.node};
            for (std::size_t i = 0; i < n; ++i) {
                if (used[first + i])
                    return make_error(hname + ": " + chunk + " reads node record " +
                                      std::to_string(first + i) + " again (chunks overlap or loop)");
                used[first + i] = true;
                if (i >= order.size())
                    return make_error(hname + ": " + chunk + " has " + std::to_string(n) +
                                      " records but its nodes declare only " + std::to_string(order.size()));
                const char* r = bytes.data() + (first + i) * kPotreeNodeBytes;
                const std::uint8_t type = std::uint8_t(r[0]), mask = std::uint8_t(r[1]);
                std::uint32_t points;
                std::int64_t off, size;
                std::memcpy(&points, r + 2, 4), std::memcpy(&off, r + 6, 8), std::memcpy(&size, r + 14, 8);
                const std::uint32_t self = order[i];
                const std::string where = hname + ": node " + o_.nodes[self].name;
                if (type > 2) return make_error(where + ": type " + std::to_string(type) + " (0, 1 or 2)");
                if (type == 1 && mask != 0) return make_error(where + ": a leaf (type 1) with children");
                if (off < 0 || size < 0) return make_error(where + ": a negative byte offset or size");
                if (type == 2 && i > 0) {  // a proxy: its own chunk comes later
                    todo.push_back({self, std::uint64_t(off), std::uint64_t(size)});
                    continue;
                }
                PotreeNode& node = o_.nodes[self];
                node.points =
                    size == 0 ? 0 : points;  // empty nodes may declare a count, as Potree reads them
                node.byte_offset = std::uint64_t(off), node.byte_size = std::uint64_t(size);
                if (type == 2) return make_error(where + ": the first node of its chunk is a proxy again");
                const int level = node.level;  // `node` moves as children are added
                for (int c = 0; c < 8; ++c) {
                    if (!(mask & (1u << c))) continue;
                    if (level + 1 > kMaxPotreeDepth)
                        return make_error(where + ": children deeper than " +
                                          std::to_string(kMaxPotreeDepth) + " levels");
                    if (o_.nodes.size() >= kMaxPotreeNodes)
                        return make_error(hname + ": more than " + std::to_string(kMaxPotreeNodes) +
                                          " nodes");
                    PotreeNode child;
                    const PotreeNode& parent = o_.nodes[self];
                    child.name = parent.name + char('0' + c);
                    child.level = parent.level + 1;
                    child.parent = std::int32_t(self);
                    const glm::dvec3 mid = 0.5 * (parent.lo + parent.hi);
                    child.lo = glm::dvec3((c & 4) ? mid.x : parent.lo.x, (c & 2) ? mid.y : parent.lo.y,
                                          (c & 1) ? mid.z : parent.lo.z);
                    child.hi = glm::dvec3((c & 4) ? parent.hi.x : mid.x, (c & 2) ? parent.hi.y : mid.y,
                                          (c & 1) ? parent.hi.z : mid.z);
                    const std::uint32_t id = std::uint32_t(o_.nodes.size());
                    o_.nodes[self].children[std::size_t(c)] = std::int32_t(id);
                    o_.nodes.push_back(std::move(child));
                    order.push_back(id);
                }
            }
            if (order.size() != n)
                return make_error(hname + ": " + chunk + " has " + std::to_string(n) +
                                  " records but its nodes declare " + std::to_string(order.size()));
        }
        return {};
    }

    // Byte ranges inside octree.bin, exactly the points' bytes, disjoint; the points add up.
    Status nodes() {
        const std::string oname = o_.octree_path.string();
        std::vector<std::pair<std::uint64_t, std::uint32_t>> ranges;
        std::uint64_t total = 0;
        for (std::uint32_t i = 0; i < o_.nodes.size(); ++i) {
            PotreeNode& n = o_.nodes[i];
            o_.depth = std::max(o_.depth, n.level);
            const std::string where = o_.hierarchy_path.string() + ": node " + n.name;
            if (n.byte_offset > o_.octree_bytes || n.byte_size > o_.octree_bytes - n.byte_offset)
                return make_error(where + ": bytes " + std::to_string(n.byte_offset) + " + " +
                                  std::to_string(n.byte_size) + " lie outside " + oname + " (" +
                                  std::to_string(o_.octree_bytes) + " bytes)");
            if (n.byte_size != std::uint64_t(n.points) * o_.point_bytes)
                return make_error(where + ": " + std::to_string(n.points) + " points of " +
                                  std::to_string(o_.point_bytes) + " bytes are not its " +
                                  std::to_string(n.byte_size) + " bytes");
            if (n.byte_size > 0) ranges.push_back({n.byte_offset, i});
            total += n.points;
        }
        std::sort(ranges.begin(), ranges.end());
        for (std::size_t i = 1; i < ranges.size(); ++i) {
            const PotreeNode& a = o_.nodes[ranges[i - 1].second];
            if (a.byte_offset + a.byte_size > ranges[i].first)
                return make_error(o_.hierarchy_path.string() + ": nodes " + a.name + " and " +
                                  o_.nodes[ranges[i].second].name + " share bytes of " + oname);
        }
        if (total != o_.points)
            return fail("\"points\" is " + std::to_string(o_.points) + " but the nodes hold " +
                        std::to_string(total));
        return {};
    }

private:
    PotreeOctree& o_;
    std::string name_;
};

// The file at `path` opened for reading: a regular file of `expected` bytes (it may not change after open).
class PointFile {
public:
    static Result<PointFile> open(const fs::path& path, std::uint64_t expected) {
        const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
        if (fd < 0) return make_error(path.string() + ": cannot open: " + std::strerror(errno));
        PointFile f(fd, path.string());
        struct stat st {};
        if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))
            return make_error(path.string() + ": not a regular file");
        if (std::uint64_t(st.st_size) != expected)
            return make_error(path.string() + ": the file changed since it was opened (" +
                              std::to_string(st.st_size) + " bytes, " + std::to_string(expected) +
                              " before)");
        return f;
    }
    PointFile(PointFile&& o) noexcept : fd_(std::exchange(o.fd_, -1)), name_(std::move(o.name_)) {}
    PointFile& operator=(PointFile&&) = delete;
    ~PointFile() {
        if (fd_ >= 0) ::close(fd_);
    }
    Status read(std::uint8_t* out, std::uint64_t bytes, std::uint64_t at) const {
        while (bytes > 0) {
            const ssize_t r = ::pread(fd_, out, std::size_t(bytes), off_t(at));
            if (r < 0 && errno == EINTR) continue;
            if (r <= 0) return make_error(name_ + ": cut short while it was read");
            out += r, bytes -= std::uint64_t(r), at += std::uint64_t(r);
        }
        return {};
    }

private:
    PointFile(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}
    int fd_ = -1;
    std::string name_;
};

template <class T>
T get(const std::uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

glm::dvec3 cloud_origin(const PotreeOctree& o) {
    if (o.has_origin) return o.origin;
    // The import rule: a far-away cloud is centred on its box.
    const glm::dvec3 c = 0.5 * (o.lo + o.hi);
    const double size = glm::length(o.hi - o.lo);
    return glm::length(c) > 1000.0 || glm::length(c) > 16.0 * size ? c : glm::dvec3(0.0);
}

// The points of `nodes` decoded: positions and colours always, the splat columns when `splats`.
// With `radii`, no axis is grown: each point's sffd_lod_radius (0 without the attribute) is appended there.
Status decode(const PotreeOctree& o, const std::vector<std::uint32_t>& nodes, bool splats, SplatCloud& c,
              std::vector<glm::dvec3>* world, std::vector<float>* radii = nullptr) {
    const std::string name = o.path.string();
    const PotreeAttribute* pos = o.attribute(kPosition.name);
    const PotreeAttribute* rgb = o.attribute(kRgb.name);
    const PotreeAttribute* alpha = o.attribute(kAlpha.name);
    const PotreeAttribute* nrm = o.attribute(kNormal.name);
    const PotreeAttribute* au = o.attribute(kAxisU.name);
    const PotreeAttribute* av = o.attribute(kAxisV.name);
    const PotreeAttribute* lod = o.attribute(kLodRadius.name);
    const PotreeAttribute* uv = o.attribute(kUv.name);
    const PotreeAttribute* uva = o.attribute(kUvAxes.name);
    if (splats && (!nrm || !au || !av))
        return make_error(name +
                          ": no \"normal\", \"sffd_axis_u\" and \"sffd_axis_v\" attributes (not written by "
                          "splatffd): read it as points, whose normals and radii are estimated");
    std::set<std::uint32_t> in(nodes.begin(), nodes.end());
    if (in.size() != nodes.size()) return make_error(name + ": a node is named twice in the set");
    std::uint64_t total = 0;
    for (const std::uint32_t i : nodes) {
        if (i >= o.nodes.size()) return make_error(name + ": node " + std::to_string(i) + " does not exist");
        total += o.nodes[i].points;
    }
    if (total > kMaxPotreePoints)
        return make_error(name + ": the set holds more than " + std::to_string(kMaxPotreePoints) + " points");
    auto file = PointFile::open(o.octree_path, o.octree_bytes);
    if (!file) return file.error();
    c.origin = cloud_origin(o);
    const std::size_t n = std::size_t(total);
    c.positions.reserve(n);
    if (rgb) c.colors.reserve(n);
    if (splats) {
        c.normals.reserve(n), c.axis_u.reserve(n), c.axis_v.reserve(n);
        if (uv) c.uvs.reserve(n);
        if (uv && uva) c.uv_axes.reserve(n);
    }
    std::vector<std::uint8_t> buf;
    for (const std::uint32_t id : nodes) {
        const PotreeNode& node = o.nodes[id];
        bool grow = false;
        for (const std::int32_t ch : node.children)
            if (ch >= 0 && !in.count(std::uint32_t(ch))) grow = !radii;
        buf.resize(std::size_t(node.byte_size));
        if (Status s = file->read(buf.data(), node.byte_size, node.byte_offset); !s) return s;
        for (std::uint32_t k = 0; k < node.points; ++k) {
            const std::uint8_t* p = buf.data() + std::size_t(k) * o.point_bytes;
            const glm::dvec3 w(double(get<std::int32_t>(p + pos->offset)) * o.scale.x + o.offset.x,
                               double(get<std::int32_t>(p + pos->offset + 4)) * o.scale.y + o.offset.y,
                               double(get<std::int32_t>(p + pos->offset + 8)) * o.scale.z + o.offset.z);
            if (world) world->push_back(w);
            c.positions.emplace_back(w - c.origin);
            if (rgb) {
                std::uint32_t col = 0;
                for (int ch = 0; ch < 3; ++ch) {
                    const std::uint32_t v = get<std::uint16_t>(p + rgb->offset + 2 * ch);
                    col |= (v > 255 ? v / 256 : v) << (8 * ch);  // Potree's reading of 8- and 16-bit colour
                }
                c.colors.push_back(col | std::uint32_t(alpha ? p[alpha->offset] : 255) << 24);
            }
            if (!splats) continue;
            const auto v3 = [&](const PotreeAttribute* a) {
                return glm::vec3(get<float>(p + a->offset), get<float>(p + a->offset + 4),
                                 get<float>(p + a->offset + 8));
            };
            glm::vec3 u = v3(au), v = v3(av);
            const glm::vec3 nv = v3(nrm);
            if (!std::isfinite(nv.x + nv.y + nv.z + u.x + u.y + u.z + v.x + v.y + v.z))
                return make_error(o.octree_path.string() + ": node " + node.name + ", point " +
                                  std::to_string(k) + ": a normal or axis is not finite");
            if ((grow || radii) && lod) {
                const float r = get<float>(p + lod->offset);
                if (!std::isfinite(r))
                    return make_error(o.octree_path.string() + ": node " + node.name + ", point " +
                                      std::to_string(k) + ": its sffd_lod_radius is not finite");
                if (radii) {
                    radii->push_back(r);
                } else {
                    const float lu = glm::length(u), lv = glm::length(v);
                    if (lu > 0 && lu < r) u *= r / lu;
                    if (lv > 0 && lv < r) v *= r / lv;
                }
            } else if (radii) {
                radii->push_back(0.0f);
            }
            c.normals.push_back(nv), c.axis_u.push_back(u), c.axis_v.push_back(v);
            if (uv) c.uvs.emplace_back(get<float>(p + uv->offset), get<float>(p + uv->offset + 4));
            if (uv && uva)
                c.uv_axes.emplace_back(get<float>(p + uva->offset), get<float>(p + uva->offset + 4),
                                       get<float>(p + uva->offset + 8), get<float>(p + uva->offset + 12));
        }
    }
    return {};
}

std::vector<std::uint32_t> all_nodes(const PotreeOctree& o) {
    std::vector<std::uint32_t> v(o.nodes.size());
    for (std::uint32_t i = 0; i < v.size(); ++i) v[i] = i;
    return v;
}

}  // namespace

Result<PotreeOctree> open_potree2(const fs::path& metadata) {
    PotreeOctree o;
    o.path = metadata;
    const std::string name = metadata.string();
    auto text = read_file(metadata, kMaxPotreeMetaBytes);
    if (!text) return text.error();
    if (Status s = check_json_depth(*text, name); !s) return s.error();
    const json m = json::parse(*text, nullptr, false);
    if (m.is_discarded()) return make_error(name + ": not valid JSON");
    Parser p(o);
    if (Status s = p.metadata(m); !s) return s.error();
    for (auto [file, out] :
         {std::pair{"hierarchy.bin", &o.hierarchy_path}, std::pair{"octree.bin", &o.octree_path}}) {
        auto r = resolve_resource(metadata, file);
        if (!r) return r.error();
        *out = *r;
    }
    std::error_code ec;
    o.octree_bytes = fs::file_size(o.octree_path, ec);
    if (ec) return make_error(o.octree_path.string() + ": " + ec.message());
    auto h = read_file(o.hierarchy_path, kMaxPotreeHierarchyBytes);
    if (!h) return h.error();
    o.hierarchy_bytes = h->size();
    if (Status s = p.hierarchy(*h); !s) return s.error();
    if (Status s = p.nodes(); !s) return s.error();
    return o;
}

Result<SplatCloud> read_potree2_nodes(const PotreeOctree& o, const std::vector<std::uint32_t>& nodes) {
    SplatCloud c;
    if (Status s = decode(o, nodes, true, c, nullptr); !s) return s.error();
    if (o.texture_path && !c.uvs.empty()) {
        std::uint64_t budget = std::uint64_t(1) << 30;
        auto img = detail::decode_image(*o.texture_path, &budget);
        if (!img) return img.error();
        // No path: it is not a file a writer could name from elsewhere (export.h writes the texels).
        c.texture.width = img->width, c.texture.height = img->height;
        c.texture.rgba8 = std::move(img->rgba8);
    }
    return c;
}

Result<SplatCloud> read_potree2_node(const PotreeOctree& o, std::uint32_t node) {
    return read_potree2_nodes(o, {node});
}

Result<PotreeNodePoints> read_potree2_node_points(const PotreeOctree& o, std::uint32_t node) {
    PotreeNodePoints out;
    if (Status s = decode(o, {node}, true, out.cloud, nullptr, &out.lod_radius); !s) return s.error();
    return out;
}

void grow_to_lod_radius(SplatCloud& cloud, std::size_t first, const std::vector<float>& lod_radius) {
    for (std::size_t k = 0; k < lod_radius.size() && first + k < cloud.size(); ++k) {
        const float r = lod_radius[k];
        glm::vec3& u = cloud.axis_u[first + k];
        glm::vec3& v = cloud.axis_v[first + k];
        const float lu = glm::length(u), lv = glm::length(v);
        if (lu > 0 && lu < r) u *= r / lu;
        if (lv > 0 && lv < r) v *= r / lv;
    }
}

Result<SplatCloud> read_potree2(const PotreeOctree& o) { return read_potree2_nodes(o, all_nodes(o)); }

std::vector<std::uint32_t> potree2_level_cut(const PotreeOctree& o, int level) {
    std::vector<std::uint32_t> v;
    for (std::uint32_t i = 0; i < o.nodes.size(); ++i)
        if (o.nodes[i].level <= level) v.push_back(i);
    return v;
}

Result<Geometry> read_potree2_geometry(const fs::path& path) {
    auto o = open_potree2(path);
    if (!o) return o.error();
    Geometry g;
    g.source = path.string();
    const bool splats = o->attribute(kNormal.name) && o->attribute(kAxisU.name) && o->attribute(kAxisV.name);
    SplatCloud c;
    if (Status s = decode(*o, all_nodes(*o), splats, c, &g.positions); !s) return s.error();
    g.normals = std::move(c.normals), g.colors = std::move(c.colors), g.uvs = std::move(c.uvs);
    g.axis_u = std::move(c.axis_u), g.axis_v = std::move(c.axis_v), g.uv_axes = std::move(c.uv_axes);
    g.has_origin = true, g.origin = c.origin;
    for (const PotreeAttribute& a : o->attributes) g.attributes.push_back(a.name);
    if (o->texture_path && !g.uvs.empty()) {
        std::uint64_t budget = std::uint64_t(1) << 30;
        auto img = detail::decode_image(*o->texture_path, &budget);
        if (!img) return img.error();
        g.splat_texture.width = img->width, g.splat_texture.height = img->height;
        g.splat_texture.rgba8 = std::move(img->rgba8);
    }
    return g;
}

std::string describe(const PotreeOctree& o) {
    std::ostringstream s;
    std::size_t leaves = 0;
    std::vector<std::uint64_t> per_level(std::size_t(o.depth) + 1, 0);
    for (const PotreeNode& n : o.nodes) {
        leaves += n.has_children() ? 0 : 1;
        per_level[std::size_t(n.level)] += n.points;
    }
    s << "format: Potree 2 octree (version " << o.version << ", encoding DEFAULT)\n";
    s << "points: " << o.points << "\n";
    s << "nodes: " << o.nodes.size() << " (" << leaves << " leaves), depth " << o.depth << "\n";
    s << "hierarchy: " << o.chunks << " chunks of " << o.step_size << " levels, " << o.hierarchy_bytes
      << " bytes\n";
    s << "octree.bin: " << o.octree_bytes << " bytes, " << o.point_bytes << " bytes a point\n";
    s << "points per level:";
    for (std::size_t l = 0; l < per_level.size(); ++l) s << (l ? ", " : " ") << per_level[l];
    s << "\n";
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "cube: [%.9g, %.9g, %.9g] .. [%.9g, %.9g, %.9g], spacing %.9g, scale %.9g\n", o.lo.x,
                  o.lo.y, o.lo.z, o.hi.x, o.hi.y, o.hi.z, o.spacing, o.scale.x);
    s << buf;
    s << "attributes:";
    for (const PotreeAttribute& a : o.attributes)
        s << " " << a.name << " (" << type_name(a.type) << " x " << a.elements << ")";
    s << "\n";
    if (o.texture_path) s << "texture: " << o.texture_path->filename().string() << "\n";
    return s.str();
}

}  // namespace sffd::assets
