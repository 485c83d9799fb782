// OFF ([ST][C][N]OFF; vertex line: x y z [nx ny nz] [r g b [a]] [s t]; face line: n i0 .. [colour])
#include <string>
#include <vector>

#include "runtime/assets/import_detail.h"
#include "runtime/core/file_io.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using namespace detail;

Result<Geometry> read_off_geometry(const fs::path& path) {
    auto text = read_file(path, kMaxTextFileBytes);
    if (!text) return text.error();
    Geometry g;
    g.source = path.string();
    std::vector<std::string_view> lines;
    for_each_line(*text, [&](std::string_view line, std::size_t) {
        const std::size_t hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
        if (line.find_first_not_of(" \t\r") != std::string_view::npos) lines.push_back(line);
        return true;
    });
    if (lines.empty()) return make_error(g.source + ": empty file (not an OFF file)");
    LineCursor head{lines[0]};
    std::string_view magic;
    head.next(magic);
    if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
        return make_error(g.source + ": not an OFF file (bad magic)");
    std::string_view prefix = magic.substr(0, magic.size() - 3);
    bool has_st = false, has_c = false, has_n = false;
    if (prefix.substr(0, 2) == "ST") {
        has_st = true;
        prefix.remove_prefix(2);
    }
    if (!prefix.empty() && prefix[0] == 'C') {
        has_c = true;
        prefix.remove_prefix(1);
    }
    if (!prefix.empty() && prefix[0] == 'N') {
        has_n = true;
        prefix.remove_prefix(1);
    }
    if (!prefix.empty())
        return make_error(g.source + ": unsupported OFF variant '" + std::string(magic) + "'");
    std::size_t li = 1;
    LineCursor counts = head;  // counts may follow the magic on the same line
    std::string_view a, b;
    if (!counts.next(a)) {
        if (lines.size() < 2) return make_error(g.source + ": truncated OFF header");
        counts = LineCursor{lines[1]};
        li = 2;
        counts.next(a);
    }
    long long nv = 0, nf = 0;
    if (!counts.next(b) || !to_long(a, nv) || !to_long(b, nf) || nv < 0 || nf < 0)
        return make_error(g.source + ": bad vertex/face counts");
    if (static_cast<unsigned long long>(nv) > lines.size() ||
        static_cast<unsigned long long>(nf) > lines.size() ||
        li + static_cast<std::size_t>(nv) + static_cast<std::size_t>(nf) > lines.size())
        return make_error(g.source + ": counts (" + std::to_string(nv) + " vertices, " + std::to_string(nf) +
                          " faces) exceed the file's " + std::to_string(lines.size()) + " lines");
    for (long long i = 0; i < nv; ++i, ++li) {
        LineCursor c{lines[li]};
        std::vector<double> d;
        std::string_view tok;
        while (c.next(tok)) {
            double x;
            if (!to_double(tok, x))
                return make_error(g.source + ": vertex " + std::to_string(i) + ": malformed number '" +
                                  std::string(tok.substr(0, 40)) + "'");
            d.push_back(x);
        }
        const std::size_t need = 3 + (has_n ? 3 : 0) + (has_c ? 3 : 0) + (has_st ? 2 : 0);
        if (d.size() < need)
            return make_error(g.source + ": vertex " + std::to_string(i) + " has too few values");
        std::size_t k = 0;
        g.positions.emplace_back(d[0], d[1], d[2]);
        k = 3;
        if (has_n) {
            g.normals.emplace_back(d[k], d[k + 1], d[k + 2]);
            k += 3;
        }
        if (has_c) {
            const std::size_t nc = d.size() - need >= 1 ? 4 : 3;
            const double scale = (d[k] > 1.0 || d[k + 1] > 1.0 || d[k + 2] > 1.0) ? 1.0 / 255.0 : 1.0;
            g.colors.push_back(pack_rgba(d[k] * scale, d[k + 1] * scale, d[k + 2] * scale,
                                         nc == 4 ? d[k + 3] * scale : 1.0));
            k += nc;
        }
        if (has_st) g.uvs.emplace_back(d[k], d[k + 1]);
    }
    for (long long i = 0; i < nf; ++i, ++li) {
        LineCursor c{lines[li]};
        std::string_view tok;
        long long n = 0;
        if (!c.next(tok) || !to_long(tok, n) || n < 0 || n > 1 << 20)
            return make_error(g.source + ": face " + std::to_string(i) + ": bad vertex count");
        std::vector<std::uint32_t> idx;
        for (long long k = 0; k < n; ++k) {
            long long x;
            if (!c.next(tok) || !to_long(tok, x))
                return make_error(g.source + ": face " + std::to_string(i) +
                                  ": too few or malformed indices");
            if (x < 0 || x >= nv)
                return make_error(g.source + ": face " + std::to_string(i) + " refers to vertex " +
                                  std::to_string(x) + " but there are only " + std::to_string(nv));
            idx.push_back(static_cast<std::uint32_t>(x));
        }
        if (idx.size() > 2 && g.triangles.size() / 3 + idx.size() - 2 > kMaxTriangles)
            return make_error(g.source + ": faces expand to more than " + std::to_string(kMaxTriangles) +
                              " triangles (the import budget)");
        for (std::size_t k = 1; k + 1 < idx.size(); ++k) {
            g.triangles.push_back(idx[0]);
            g.triangles.push_back(idx[k]);
            g.triangles.push_back(idx[k + 1]);
        }
    }
    g.attributes = {"position"};
    if (has_n) g.attributes.push_back("normal");
    if (has_c) g.attributes.push_back("color");
    if (has_st) g.attributes.push_back("texcoord");
    if (auto s = check_geometry(g); !s) return s.error();
    return g;
}

}  // namespace sffd::assets
