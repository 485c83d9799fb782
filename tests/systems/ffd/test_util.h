// Shared helpers for the FFD tests: point generators, a NumPy .npy reader, lattice shortcuts.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "systems/ffd/components.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd::test {

struct Cloud {
    glm::dvec3 origin{0.0};
    std::vector<glm::vec3> p, n, u, v;
    std::size_t size() const { return p.size(); }
};

// Fibonacci sphere (the paper's benchmark points): unit radius, normals outward, tangent axes radius r.
inline Cloud fibonacci_sphere(std::size_t count, double radius = 1.0, double splat_radius = 0.01) {
    Cloud c;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (std::size_t i = 0; i < count; ++i) {
        const double y = 1.0 - 2.0 * (double(i) + 0.5) / double(count);
        const double r = std::sqrt(1.0 - y * y), th = golden * double(i);
        const glm::dvec3 n(r * std::cos(th), y, r * std::sin(th));
        glm::dvec3 t =
            glm::abs(n.x) < 0.9 ? glm::cross(n, glm::dvec3(1, 0, 0)) : glm::cross(n, glm::dvec3(0, 1, 0));
        t = glm::normalize(t);
        const glm::dvec3 b = glm::cross(n, t);
        c.p.push_back(glm::vec3(n * radius));
        c.n.push_back(glm::vec3(n));
        c.u.push_back(glm::vec3(t * splat_radius));
        c.v.push_back(glm::vec3(b * splat_radius));
    }
    return c;
}

// Random points in [lo, hi]^3 with random unit normals and tangent axes.
inline Cloud random_cloud(std::size_t count, double lo, double hi, unsigned seed = 1) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> pos(lo, hi), dir(-1.0, 1.0);
    Cloud c;
    for (std::size_t i = 0; i < count; ++i) {
        glm::dvec3 n;
        do n = glm::dvec3(dir(rng), dir(rng), dir(rng));
        while (glm::length(n) < 0.1);
        n = glm::normalize(n);
        glm::dvec3 t =
            glm::normalize(glm::cross(n, glm::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
        c.p.push_back(glm::vec3(pos(rng), pos(rng), pos(rng)));
        c.n.push_back(glm::vec3(n));
        c.u.push_back(glm::vec3(t * 0.02));
        c.v.push_back(glm::vec3(glm::cross(n, t) * 0.03));
    }
    return c;
}

// A twist about the lattice's T axis through its centre, angle proportional to height (Blender peer case).
inline void twist_about_t(Lattice& l, double rate) {
    const glm::dvec3 centre = l.origin + 0.5 * (l.axes[0] + l.axes[1] + l.axes[2]);
    const glm::dvec3 a = glm::normalize(l.axes[1]);
    for (std::size_t c = 0; c < l.size(); ++c) {
        const glm::dvec3 r = l.rest[c] - centre;
        const double h = glm::dot(r, a), ang = rate * h;
        const glm::dvec3 par = a * h, perp = r - par;
        const glm::dvec3 rotated = perp * std::cos(ang) + glm::cross(a, perp) * std::sin(ang) + par;
        l.current[c] = centre + rotated;
    }
}

// Random displacement of every control point (or of those with index % stride == 0).
inline void jitter(Lattice& l, double amount, unsigned seed = 7, std::size_t stride = 1) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> d(-amount, amount);
    for (std::size_t c = 0; c < l.size(); c += stride)
        l.current[c] = l.rest[c] + glm::dvec3(d(rng), d(rng), d(rng));
}

// NumPy v1/v2 .npy reader for little-endian float64 C-order arrays (what the PyGeM data uses).
inline bool read_npy_f64(const std::string& path, std::vector<double>& out, std::vector<std::size_t>& shape) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return false;
    char magic[6];
    f.read(magic, 6);
    if (std::memcmp(magic, "\x93NUMPY", 6) != 0) return false;
    unsigned char ver[2];
    f.read(reinterpret_cast<char*>(ver), 2);
    std::uint32_t hlen = 0;
    if (ver[0] == 1) {
        unsigned char b[2];
        f.read(reinterpret_cast<char*>(b), 2);
        hlen = b[0] | (b[1] << 8);
    } else {
        unsigned char b[4];
        f.read(reinterpret_cast<char*>(b), 4);
        hlen = b[0] | (b[1] << 8) | (b[2] << 16) | (std::uint32_t(b[3]) << 24);
    }
    std::string header(hlen, '\0');
    f.read(header.data(), hlen);
    if (header.find("'<f8'") == std::string::npos ||
        header.find("'fortran_order': False") == std::string::npos)
        return false;
    const auto open = header.find('('), close = header.find(')');
    shape.clear();
    std::size_t total = 1;
    for (std::size_t pos = open + 1; pos < close;) {
        const std::size_t comma = std::min(header.find(',', pos), close);
        const std::string tok = header.substr(pos, comma - pos);
        if (tok.find_first_of("0123456789") != std::string::npos) {
            shape.push_back(std::stoul(tok));
            total *= shape.back();
        }
        pos = comma + 1;
    }
    out.resize(total);
    f.read(reinterpret_cast<char*>(out.data()), std::streamsize(total * sizeof(double)));
    return bool(f);
}

// The PyGeM sphere case (../shared/testdata/pygem/README.md) in this project's convention.
inline Lattice pygem_lattice() {
    Lattice l = make_lattice({-20, -55, -45},
                             {glm::dvec3(42.8063059153889, 11.646857029613432, -7.547906677343428),
                              glm::dvec3(-22.93983020197609, 86.93332436601615, 4.0449109974793),
                              glm::dvec3(15.62833599002373, 0.0, 88.63269777109872)},
                             {2, 1, 1}, LatticeBasis::bernstein);
    l.current[l.index(2, 0, 0)] = glm::dvec3(52.89292975866434, -77.5023195297039, -149.24138528905655);
    return l;
}

}  // namespace sffd::ffd::test
