// Helpers shared by the animation tests.
#pragma once

#include <cstring>

#include <glm/glm.hpp>

#include "systems/ffd/components.h"

namespace sffd::test {

// A regular lattice with rest == current, P0[i][j][k] = X0 + (i/l) S + (j/m) T + (k/n) U.
inline Lattice make_lattice(glm::ivec3 divisions, glm::dvec3 origin = glm::dvec3(-1.0),
                            glm::dvec3 size = glm::dvec3(2.0)) {
    Lattice l;
    l.origin = origin;
    l.axes = {glm::dvec3(size.x, 0, 0), glm::dvec3(0, size.y, 0), glm::dvec3(0, 0, size.z)};
    l.divisions = divisions;
    for (int i = 0; i <= divisions.x; ++i)
        for (int j = 0; j <= divisions.y; ++j)
            for (int k = 0; k <= divisions.z; ++k)
                l.rest.push_back(origin + (double(i) / divisions.x) * l.axes[0] +
                                 (double(j) / divisions.y) * l.axes[1] +
                                 (double(k) / divisions.z) * l.axes[2]);
    l.current = l.rest;
    return l;
}

inline bool same_bits(const glm::dvec3& a, const glm::dvec3& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace sffd::test
