// A textured box with a known uv map: a 2 x 1 x 0.5 box whose six faces each map to their own
// sheared, non-uniformly scaled parallelogram of one texture, written as OBJ + MTL + PNG. The analytic uv
// of a point on a face and its derivative along a vector are what mesh sampling must reproduce.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <stb/stb_image_write.h>

namespace sffd::test {

struct BoxFace {
    glm::dvec3 corner, e1, e2;  // the face: corner + s e1 + t e2, s, t in [0, 1]; e1 x e2 points outwards
    glm::dvec2 uv0, f1, f2;     // its uv: uv0 + s f1 + t f2 (texture convention: v = 0 is texel row 0)

    glm::dvec3 normal() const { return glm::normalize(glm::cross(e1, e2)); }
    // Face coordinates of a point (e1 and e2 are perpendicular).
    glm::dvec2 st(const glm::dvec3& x) const {
        return {glm::dot(x - corner, e1) / glm::dot(e1, e1), glm::dot(x - corner, e2) / glm::dot(e2, e2)};
    }
    glm::dvec2 uv(const glm::dvec3& x) const {
        const glm::dvec2 p = st(x);
        return uv0 + p.x * f1 + p.y * f2;
    }
    // The change of uv along a vector d (its component in the face's plane; the map is affine).
    glm::dvec2 duv(const glm::dvec3& d) const {
        return glm::dot(d, e1) / glm::dot(e1, e1) * f1 + glm::dot(d, e2) / glm::dot(e2, e2) * f2;
    }
};

inline std::array<BoxFace, 6> textured_box_faces() {
    std::array<BoxFace, 6> f;
    const glm::dvec3 c[6] = {{-1, -0.5, 0.25},  {1, -0.5, -0.25}, {1, -0.5, 0.25},
                             {-1, -0.5, -0.25}, {-1, 0.5, 0.25},  {-1, -0.5, -0.25}};
    const glm::dvec3 e1[6] = {{2, 0, 0}, {-2, 0, 0}, {0, 0, -0.5}, {0, 0, 0.5}, {2, 0, 0}, {2, 0, 0}};
    const glm::dvec3 e2[6] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 0, -0.5}, {0, 0, 0.5}};
    for (int k = 0; k < 6; ++k) {
        f[std::size_t(k)] = {c[k],
                             e1[k],
                             e2[k],
                             glm::dvec2(0.05 + 0.15 * k, 0.1 + 0.1 * (k % 2)),
                             glm::dvec2(0.12, 0.02 * k - 0.03),
                             glm::dvec2(0.01 * (k - 2), 0.35 + 0.05 * k)};
    }
    return f;
}

// The face a point lies on, by its normal (mesh sampling gives each sample its triangle's normal).
inline const BoxFace* box_face_of(const std::array<BoxFace, 6>& faces, const glm::dvec3& normal) {
    for (const BoxFace& f : faces)
        if (glm::dot(f.normal(), normal) > 0.999) return &f;
    return nullptr;
}

// A checker of `cells` x `cells` squares (black / near-white sRGB), `size` x `size` texels.
inline std::vector<std::uint8_t> checker_texels(int size, int cells) {
    std::vector<std::uint8_t> px(std::size_t(size) * std::size_t(size) * 4);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const bool on = ((x * cells / size) + (y * cells / size)) % 2 == 0;
            std::uint8_t* p = &px[(std::size_t(y) * std::size_t(size) + std::size_t(x)) * 4];
            p[0] = on ? 230 : 20, p[1] = on ? 220 : 30, p[2] = on ? 200 : 60, p[3] = 255;
        }
    return px;
}

// Writes box.obj (24 vertices, 6 quads, OBJ's flipped v), box.mtl and checker.png into `dir`; returns the
// OBJ's path.
inline std::filesystem::path write_textured_box(const std::filesystem::path& dir, int texture_size = 256,
                                                int cells = 16) {
    std::filesystem::create_directories(dir);
    const std::vector<std::uint8_t> px = checker_texels(texture_size, cells);
    stbi_write_png((dir / "checker.png").string().c_str(), texture_size, texture_size, 4, px.data(),
                   texture_size * 4);
    std::ofstream(dir / "box.mtl") << "newmtl checker\nKd 1 1 1\nmap_Kd checker.png\n";
    std::ostringstream obj;
    obj.precision(17);
    obj << "mtllib box.mtl\nusemtl checker\n";
    for (const BoxFace& f : textured_box_faces())
        for (const glm::dvec2 st : {glm::dvec2(0, 0), glm::dvec2(1, 0), glm::dvec2(1, 1), glm::dvec2(0, 1)}) {
            const glm::dvec3 x = f.corner + st.x * f.e1 + st.y * f.e2;
            const glm::dvec2 uv = f.uv0 + st.x * f.f1 + st.y * f.f2;
            obj << "v " << x.x << ' ' << x.y << ' ' << x.z << "\nvt " << uv.x << ' ' << 1.0 - uv.y << '\n';
        }
    for (int k = 0; k < 6; ++k) {
        obj << 'f';
        for (int i = 1; i <= 4; ++i) obj << ' ' << 4 * k + i << '/' << 4 * k + i;
        obj << '\n';
    }
    std::ofstream(dir / "box.obj") << obj.str();
    return dir / "box.obj";
}

}  // namespace sffd::test
