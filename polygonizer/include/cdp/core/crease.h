// Creases and corners of a field built with min, max and abs (a CSG shape), from its pieces
// (Field::pieces): a crease is where two pieces are zero, a corner where three are. The first
// building block of crease-aware meshing: a point is moved onto a crease or corner by Newton's
// method on the pieces' equations together.
#pragma once

#include <cdp/core/field.h>

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace cdp {

struct CreaseOptions {
  int max_iterations = 40;
  // Converged when every piece's |F_i| / |grad F_i| is below this. Non-positive: 1e-10 times the
  // field's bounding-box diagonal (as the Newton projection onto the surface).
  double tolerance = 0;
  // One step moves at most this far. Non-positive: 0.1 diagonal.
  double max_step = 0;
};

// DependentGradients: the pieces' gradients are (nearly) linearly dependent there (pieces
// tangent to each other, or three pieces meeting along a line), so the crease is not defined.
enum class CreaseStatus { Converged, MaxIterations, DependentGradients, NotFinite };

// \return the status's name: "converged", "max_iterations", "dependent_gradients" or "not_finite"
//         ("unknown" for a value outside the enum).
const char* to_string(CreaseStatus status);

struct CreaseProjection {
  Vec3 point = Vec3::Zero();
  CreaseStatus status = CreaseStatus::MaxIterations;
  int iterations = 0;
  double residual = 0;  // the largest |F_i| / |grad F_i| at `point`
  // Each piece's gradient at `point` (the first 2 or 3, in the order given), from the evaluation
  // that measured the residual: the numbers Field::piece_first_order gives there, bit for bit.
  std::array<Vec3, 3> gradients{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  bool ok() const { return status == CreaseStatus::Converged; }
};

// Moves `start` onto the common zero set of the pieces `branches` (from Field::pieces): with two,
// the nearest point of their crease curve (minimum-norm Newton steps, J^T (J J^T)^-1 F); with
// three, their corner (Newton on the 3 x 3 system). Throws InvalidInputError for a number of
// pieces other than 2 or 3.
// \pre field.bounds() is valid where options.tolerance or options.max_step is left non-positive
//      (their defaults scale with its diagonal).
// \return the last point with its status, iterations and residual; ok() when it converged.
// \throw InvalidInputError for a number of pieces other than 2 or 3, or a branch the field refuses
//        (Field::piece_first_order).
// \throw what the field's evaluations throw, unchanged.
CreaseProjection project_to_crease(const Field& field, const Vec3& start,
                                   std::span<const std::vector<std::uint8_t>> branches,
                                   const CreaseOptions& options = {});
// The same from a start where each piece's value and gradient are known already (at_start[i]
// for branches[i]: from Field::pieces or pieces_first_order at `start`), which are not
// evaluated again; empty at_start: evaluated, as above.
// \throw as above, and InvalidInputError for a non-empty at_start of another size than branches.
CreaseProjection project_to_crease(const Field& field, const Vec3& start,
                                   std::span<const std::vector<std::uint8_t>> branches,
                                   std::span<const std::pair<double, Vec3>> at_start, const CreaseOptions& options = {});

// Moves `start` onto the curve where the piece `branch` is zero and branch point k switches
// (Field::branch_switch): the crease between that piece and the one that differs from it at k
// only, and its continuation where the two become one function (the switch hidden by another
// branch: a box's edge entering a smooth union's blend), where project_to_crease has two equal
// gradients. Minimum-norm Newton steps as project_to_crease's; NotFinite where the switch is
// not defined.
// \pre as project_to_crease.
// \return as project_to_crease; NotFinite also for k not below the model's number of branch points.
// \throw InvalidInputError for a branch the field refuses (Field::piece_first_order).
// \throw what the field's evaluations throw, unchanged.
CreaseProjection project_to_seam(const Field& field, const Vec3& start, const std::vector<std::uint8_t>& branch,
                                 std::size_t k, const CreaseOptions& options = {});

}  // namespace cdp
