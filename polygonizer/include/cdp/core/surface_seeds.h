// Seeds on every component of the surface inside the field's box, from sign changes of F on a
// coarse grid. A component that fits between grid points (smaller than about one cell) can be
// missed; raise `resolution` to catch smaller ones.
#pragma once

#include <cdp/core/field.h>

#include <array>
#include <cstddef>
#include <vector>

namespace cdp {

struct SeedOptions {
  int resolution = 32;  // grid cells along the longest side of the box
  // Reject fields whose surface leaves the box (F < 0 on the box's boundary).
  bool require_closed_in_box = true;
  // Threads sampling the grid of a thread-safe field (Field::thread_safe): 0 all cores (at most
  // 8), 1 the caller's only. The grid is the same on any number.
  int threads = 0;
};

struct SurfaceSeed {
  Vec3 point;   // see the functions below for whether it lies on the surface
  int cluster;  // crossings of one 26-connected group of crossed grid cells share a cluster id
};

// A seed grid node where |F| is under this share of the grid's spacing has F zero to rounding (a
// node on the common face of two boxes that touch is exactly 0; rotated, a few units in the last
// place): see sample_seed_grid's touching nodes.
inline constexpr double kTouchingZero = 1e-12;

// F sampled at the nodes of the seed grid: cubic cells of side h from the box's min corner, n
// cells per axis (the last layer may reach past the box's max corner).
struct SeedGrid {
  Vec3 origin = Vec3::Zero();
  double h = 1;
  std::array<int, 3> n{1, 1, 1};
  std::vector<double> values;  // node (i, j, k) at index(i, j, k)
  std::size_t non_finite = 0;  // nodes where F was NaN or infinite (sample_seed_grid's rule)
  // Nodes where F is 0 (to rounding) between inside ones and next to no outside one, counted as
  // inside: the surface only touches them (two solids touching there; sample_seed_grid's rule).
  std::size_t touching = 0;
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * (n[1] + 1) + j) * (n[0] + 1) + i;
  }
  Vec3 point(int i, int j, int k) const { return origin + h * Vec3(i, j, k); }
  double value(int i, int j, int k) const { return values[index(i, j, k)]; }
  // Calls fn(a, b) with the end nodes a = {i, j, k}, b of every grid edge whose values differ in
  // sign (F < 0 counts as inside), nodes in index order, then axes x, y, z.
  template <class Fn>
  void for_each_sign_change(Fn&& fn) const {
    for (int k = 0; k <= n[2]; ++k)
      for (int j = 0; j <= n[1]; ++j)
        for (int i = 0; i <= n[0]; ++i)
          for (int axis = 0; axis < 3; ++axis) {
            const std::array<int, 3> a{i, j, k}, b{i + (axis == 0), j + (axis == 1), k + (axis == 2)};
            if (b[0] > n[0] || b[1] > n[1] || b[2] > n[2]) continue;
            if ((value(i, j, k) < 0) == (value(b[0], b[1], b[2]) < 0)) continue;
            fn(a, b);
          }
  }
};

// Samples the grid (one batched evaluation). A node where F is NaN or +infinity counts as
// outside (its value becomes the largest double), one at -infinity as inside (the lowest), so
// that a function undefined away from its surface (a NaN far out in the box) is meshed. A node
// where F is 0 to rounding, with a neighbour inside and none outside, counts as inside (its
// value becomes the smallest negative normal double): no surface passes there (the common face
// of two solids that touch).
// \return the grid; the count of non-finite nodes in SeedGrid::non_finite, of the touching ones
//         in SeedGrid::touching.
// \throw InvalidInputError for a resolution below 2 or a grid of more than 2^26 nodes.
// \throw NoSurfaceError for a field whose box is not valid, where a NaN node lies next to an inside
//        node (the surface may pass where F is undefined) or (with require_closed_in_box) F is
//        negative on the box's boundary.
SeedGrid sample_seed_grid(const Field& field, const SeedOptions& options = {});

// Every grid edge with a sign change, its crossing point linearly interpolated (not on the
// surface: cheap, for coverage checks "is this crossing already meshed?").
// \return the crossings in a deterministic order, clusters numbered from 0 in order of first
//         appearance.
// \throw NoSurfaceError when the field is NaN on the grid, has no zero crossing, or (with
//        require_closed_in_box) leaves the box; InvalidInputError as sample_seed_grid.
std::vector<SurfaceSeed> find_surface_crossings(const Field& field, const SeedOptions& options = {});

// One seed per cluster, on the surface (bisected along its grid edge, then Newton-projected).
// \return for each cluster, the first crossing whose projection converges.
// \throw as find_surface_crossings.
std::vector<SurfaceSeed> find_surface_seeds(const Field& field, const SeedOptions& options = {});
// The same from a grid already sampled (with `resolution`, named in errors), for callers that
// also use the grid's values and should not pay for sampling it twice.
std::vector<SurfaceSeed> find_surface_seeds(const Field& field, const SeedGrid& grid, int resolution);

// Grid spacing the functions above use for a field and options.
double seed_grid_spacing(const Field& field, const SeedOptions& options = {});

}  // namespace cdp
