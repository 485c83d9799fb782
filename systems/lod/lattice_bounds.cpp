#include "systems/lod/lattice_bounds.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

namespace sffd::lod {

namespace {

using ffd::Box;

// A Bézier control polygon restricted to [a, b] ⊂ [0, 1]: de Casteljau at b keeps the part over [0, b],
// then at a / b the part of that over [a, b]. O(n²).
void restrict_bezier(std::vector<glm::dvec3>& c, double a, double b) {
    const std::size_t n = c.size() - 1;
    if (n == 0 || (a <= 0.0 && b >= 1.0)) return;
    std::vector<glm::dvec3> w = c, left(n + 1);
    left[0] = w[0];
    for (std::size_t r = 1; r <= n; ++r) {
        for (std::size_t i = 0; i + r <= n; ++i) w[i] = (1.0 - b) * w[i] + b * w[i + 1];
        left[r] = w[0];
    }
    if (!(b > 0.0)) {
        c.assign(n + 1, left[0]);
        return;
    }
    const double t = std::clamp(a / b, 0.0, 1.0);
    w = left;
    c[n] = w[n];
    for (std::size_t r = 1; r <= n; ++r) {
        for (std::size_t i = 0; i + r <= n; ++i) w[i] = (1.0 - t) * w[i] + t * w[i + 1];
        c[n - r] = w[n - r];
    }
}

// The control grid (flat index (i*(m+1)+j)*(n+1)+k) restricted to [q0, q1] along every axis.
std::vector<glm::dvec3> restrict_grid(const Lattice& l, std::vector<glm::dvec3> grid, const glm::dvec3& q0,
                                      const glm::dvec3& q1) {
    const glm::ivec3 d = l.divisions;
    std::vector<glm::dvec3> line;
    for (int axis = 0; axis < 3; ++axis) {
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        for (int p = 0; p <= d[a1]; ++p)
            for (int q = 0; q <= d[a2]; ++q) {
                line.resize(std::size_t(d[axis]) + 1);
                glm::ivec3 at(0);
                at[a1] = p, at[a2] = q;
                for (int r = 0; r <= d[axis]; ++r) {
                    at[axis] = r;
                    line[std::size_t(r)] = grid[l.index(at.x, at.y, at.z)];
                }
                restrict_bezier(line, q0[axis], q1[axis]);
                for (int r = 0; r <= d[axis]; ++r) {
                    at[axis] = r;
                    grid[l.index(at.x, at.y, at.z)] = line[std::size_t(r)];
                }
            }
    }
    return grid;
}

Box box_of(const std::vector<glm::dvec3>& points) {
    Box b;
    for (const glm::dvec3& p : points) b.add(p);
    return b;
}

Box unite(Box a, const Box& b) {
    if (b.empty) return a;
    if (a.empty) return b;
    a.lo = glm::min(a.lo, b.lo), a.hi = glm::max(a.hi, b.hi);
    return a;
}

}  // namespace

ffd::Box lattice_node_bounds(const Lattice& l, const Box& box, bool weighted) {
    if (box.empty || !ffd::validate(l).ok()) return box;
    // The box's range in local coordinates (the box of its corners': exact for the parallelepiped).
    glm::dvec3 plo(INFINITY), phi(-INFINITY);
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 p((c & 4) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
                           (c & 1) ? box.hi.z : box.lo.z);
        const glm::dvec3 s = ffd::local_coords(l, p);
        plo = glm::min(plo, s), phi = glm::max(phi, s);
    }
    const double slack = ffd::kInsideSlack;
    for (int a = 0; a < 3; ++a)
        if (phi[a] < -slack || plo[a] > 1.0 + slack) return box;  // wholly outside: nothing moves
    const bool reaches_out = glm::any(glm::lessThan(plo, glm::dvec3(-slack))) ||
                             glm::any(glm::greaterThan(phi, glm::dvec3(1.0 + slack)));
    const glm::dvec3 q0 = glm::clamp(plo, 0.0, 1.0), q1 = glm::clamp(phi, 0.0, 1.0);
    const bool uniform = ffd::rest_is_uniform(l);
    std::vector<glm::dvec3> moved(l.size());
    for (std::size_t c = 0; c < moved.size(); ++c) moved[c] = l.current[c] - l.rest[c];
    Box disp, hull;
    bool sums_to_one = true;
    if (l.basis == LatticeBasis::bernstein) {
        disp = box_of(restrict_grid(l, std::move(moved), q0, q1));
        if (uniform) hull = box_of(restrict_grid(l, l.current, q0, q1));
    } else {
        // The B-spline window per axis: every index whose N(l s − i) is non-zero somewhere in the range
        // (widened by the slack, so rounding in the kernels cannot reach a neighbour outside it).
        glm::ivec3 w0, w1;
        for (int a = 0; a < 3; ++a) {
            const int n = l.divisions[a];
            w0[a] = int(std::floor(n * (q0[a] - slack))) - 1;
            w1[a] = int(std::floor(n * (q1[a] + slack))) + 2;
            if (w0[a] < 0 || w1[a] > n) sums_to_one = false;
            w0[a] = std::max(w0[a], 0), w1[a] = std::min(w1[a], n);
        }
        for (int i = w0.x; i <= w1.x; ++i)
            for (int j = w0.y; j <= w1.y; ++j)
                for (int k = w0.z; k <= w1.z; ++k) {
                    const std::size_t c = l.index(i, j, k);
                    disp.add(moved[c]);
                    if (uniform && sums_to_one) hull.add(l.current[c]);
                }
    }
    if (weighted || !sums_to_one) disp.add(glm::dvec3(0.0));
    Box out{box.lo + disp.lo, box.hi + disp.hi, false};
    if (!hull.empty) {
        if (weighted) hull = unite(hull, box);
        out.lo = glm::max(out.lo, hull.lo), out.hi = glm::min(out.hi, hull.hi);
    }
    const glm::dvec3 pad(slack * (glm::length(l.axes[0]) + glm::length(l.axes[1]) + glm::length(l.axes[2])));
    out.lo -= pad, out.hi += pad;
    return reaches_out ? unite(out, box) : out;
}

ffd::Box lattice_node_bounds(std::span<const Lattice* const> lattices, const Box& box, bool weighted) {
    Box b = box;
    for (const Lattice* l : lattices)
        if (l) b = lattice_node_bounds(*l, b, weighted);
    return b;
}

CutTree deformed_cut_tree(const CutTree& tree, std::span<const Lattice* const> lattices, bool weighted) {
    CutTree out = tree;
    // A streamed SOG leaf's levels share its box: each distinct box is bounded once (a bound through an
    // 11^3 lattice costs about a millisecond).
    std::map<std::array<double, 6>, Box> done;
    for (CutNode& n : out.nodes) {
        const std::array<double, 6> key{n.lo.x, n.lo.y, n.lo.z, n.hi.x, n.hi.y, n.hi.z};
        auto it = done.find(key);
        if (it == done.end())
            it = done.emplace(key, lattice_node_bounds(lattices, Box{n.lo, n.hi, false}, weighted)).first;
        const Box b = it->second;
        const double before = glm::length(n.hi - n.lo), after = glm::length(b.hi - b.lo);
        if (before > 0.0 && after > before) n.size *= after / before;
        n.lo = b.lo, n.hi = b.hi;
    }
    return out;
}

}  // namespace sffd::lod
