// Lattice operations (paper eqs. 23-24 and lattice management). All edit `current` (and `rest` where the
// operation says so) of a Lattice passed by reference: callers holding a registry go through
// registry.patch<Lattice>(e) so the deformation phase sees the change.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

using Selection = std::vector<std::size_t>;  // flat control-point indices

Selection all_control_points(const Lattice& lattice);
// Every (i,j,k) with lo <= (i,j,k) <= hi (inclusive, clamped to the grid).
Selection select_range(const Lattice& lattice, glm::ivec3 lo, glm::ivec3 hi);
glm::dvec3 centroid(const Lattice& lattice, const Selection& selection);  // of current positions

// Stretch (eq. 23): P' = P + v for the selection.
void stretch(Lattice& lattice, const Selection& selection, const glm::dvec3& v);
// Twist (eq. 24): P' = C + R(axis, angle) (P − C); pivot C defaults to the selection's centroid.
void twist(Lattice& lattice, const Selection& selection, const glm::dvec3& axis, double angle,
           std::optional<glm::dvec3> pivot = std::nullopt);
// Graded twist: each selected point rotates about the axis through the pivot by rate · h, h its height
// along the axis (measured on its rest position), i.e. a real twist of the selection.
void twist_graded(Lattice& lattice, const Selection& selection, const glm::dvec3& axis, double rate,
                  std::optional<glm::dvec3> pivot = std::nullopt);
// Back to rest.
void reset(Lattice& lattice);

// An axis-aligned lattice around points (positions relative to `origin`), grown by `padding` × the
// box's largest extent on every side. Flat or collinear input (or a single point) is safe: a degenerate
// axis gets a minimum thickness of 1e-3 × the largest extent (or 1e-3 when all points coincide).
Result<Lattice> fit_lattice(const std::vector<glm::vec3>& positions, const glm::dvec3& origin,
                            glm::ivec3 divisions, LatticeBasis basis = LatticeBasis::bernstein,
                            double padding = 0.05);

// How a lattice is fitted around a cloud (the `splatffd convert/deform --lattice fit:…` spec, the editor's
// add/refit). `oriented`: the box along the principal axes of the points (PCA of their covariance), each
// principal axis assigned to the world axis it is closest to (sign included), so divisions (l, m, n) still
// run roughly along x, y, z and an axis-aligned object gets its axis-aligned box.
enum class FitShape : std::uint8_t { box, oriented };
struct FitOptions {
    glm::ivec3 divisions{10, 10, 10};  // as the built-in scenes' lattices (11 control points per axis)
    LatticeBasis basis = LatticeBasis::bernstein;
    double padding = 0.05;  // × the box's largest extent, on every side
    FitShape shape = FitShape::box;
};
Result<Lattice> fit_lattice(const std::vector<glm::vec3>& positions, const glm::dvec3& origin,
                            const FitOptions& options);

// "fit[:L,M,N][,pad=P][,obb|,box][,bspline|,bernstein]" (one division count D means D,D,D). Errors name
// the offending part, e.g. "fit:4,x: divisions must be integers in 1..64".
bool is_fit_spec(std::string_view text);  // "fit" or "fit:…"
Result<FitOptions> parse_fit_spec(std::string_view text);
std::string fit_spec_string(const FitOptions& options);  // canonical form, parses back to the same options

// The current shape becomes the rest lattice (the deformation becomes the identity). Pass the cloud's
// positions/normals/axes to bake the current deformation into them first, so nothing moves on screen.
struct BakeTarget {
    std::vector<glm::vec3>* positions = nullptr;
    std::vector<glm::vec3>* normals = nullptr;
    std::vector<glm::vec3>* axis_u = nullptr;
    std::vector<glm::vec3>* axis_v = nullptr;
    glm::dvec3 origin{0.0};
};
Status apply_as_rest(Lattice& lattice, const BakeTarget* bake = nullptr);

// Higher resolution, same deformation. Bernstein: degree elevation, any divisions >= the current ones
// (exact). B-spline: each axis kept or doubled (subdivision; exact when the boundary layer of control
// points is at rest — grid points outside the lattice do not exist in this convention; otherwise the
// result is exact inside and `*exact` is set to false).
Result<Lattice> raise_resolution(const Lattice& lattice, glm::ivec3 divisions, bool* exact = nullptr);
// Lower resolution: least-squares fit of the new displacements to the current deformation, sampled on a
// tensor grid inside the lattice (separable, so each axis is a small solve).
Result<Lattice> lower_resolution(const Lattice& lattice, glm::ivec3 divisions);

}  // namespace sffd::ffd
