// Small maths the Gaussian tests share when they compare covariances and Jacobians.
#pragma once

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>

namespace sffd::test {

// The largest absolute entry of `a` (the max norm the relative covariance errors are measured in).
inline double max_abs(const glm::dmat3& a) {
    double m = 0.0;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) m = std::max(m, std::abs(a[c][r]));
    return m;
}

}  // namespace sffd::test
