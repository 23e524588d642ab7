// Options shared by the two cell-partitioning baselines, Marching Cubes and Marching Tetrahedra,
// and the resolution of the lattice they run on. See baselines/README.md.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/cancel.h>
#include <cdp/core/progress.h>

#include <array>
#include <cstddef>

namespace cdp {

// How the cubes to polygonize are found.
enum class Traversal {
  // Bloomenthal's continuation: start from the cubes of the surface seeds and follow the surface
  // from cube to cube through faces it crosses; only cubes near the surface cost evaluations.
  // Then every sign change of the seed grid the mesh does not cover starts a walk too, so a
  // component the seeds miss (several can share one seed cluster) is still meshed; the mesh is
  // the grid traversal's whenever every component crosses an edge of the seed grid.
  Continuation,
  // Every cube of the lattice over the field's box, slab by slab.
  Grid,
};

// How Marching Cubes decides a cube face whose inside (F < 0) corners sit on one diagonal and
// outside corners on the other. Both cubes sharing the face see the same four values and make
// the same decision, so every rule gives crack-free meshes.
enum class FaceAmbiguity {
  // Nielson & Hamann's asymptotic decider: the inside corners are joined across the face when
  // the bilinear interpolant is negative at its saddle point.
  AsymptoticDecider,
  JoinInside,      // always join the inside corners (separate the outside ones)
  SeparateInside,  // always separate the inside corners
};

struct MarchingOptions {
  // Edge length of the cubic cells. Give either this or `precision`; with neither, the cell is
  // 1/64 of the longest side of the field's box.
  double cell_size = 0;
  // The paper's Marching Tetrahedra precision P in 0..5 for data-driven (variational) models:
  // cell = field.constraint_spacing() * s(P), s = 1, 0.7, 0.6, 0.5, 0.4, 0.3. Negative: unused.
  int precision = -1;
  Traversal traversal = Traversal::Continuation;
  FaceAmbiguity face_ambiguity = FaceAmbiguity::AsymptoticDecider;  // Marching Cubes only
  // Crossing points on lattice edges are found by a bracketed root search (Illinois regula
  // falsi with bisection safeguard) to within this distance along the edge of the true crossing
  // of the field. Non-positive: 1e-6 of the cell size.
  double root_tolerance = 0;
  // Cells of the coarse sign-change grid that seeds the continuation (longest side of the box).
  int seed_resolution = 32;
  // Threads sampling that grid for a thread-safe field (Field::thread_safe): 0 all cores (at
  // most 8), 1 the caller's only. The mesh is the same on any number.
  int threads = 0;
  // Reject fields whose surface leaves the lattice (F < 0 on its outer boundary) with
  // NoSurfaceError; when false the mesh is clipped there and left open.
  bool require_closed_in_box = true;
  // Bounds: hitting one throws LimitExceededError (the grid traversal checks max_cubes before
  // evaluating anything).
  std::size_t max_cubes = 1'000'000'000;
  std::size_t max_triangles = 50'000'000;
  // Called now and then with an estimate of the fraction done.
  ProgressCallback progress;
  // Cancels the run from outside (cdp/core/cancel.h): it ends with CancelledError.
  CancelToken cancel;
};

// s(P) of the paper's precision convention; InvalidInputError outside 0..5.
double precision_scale(int precision);

// The cell size the options ask for on this field. Throws InvalidInputError for a non-positive
// or non-finite size, for both cell_size and precision given, and for a precision on a field
// without constraint_spacing() (not a variational, data-driven model).
double resolve_cell_size(const Field& field, const MarchingOptions& options);

// The lattice both traversals share: corners origin + h (i, j, k) with origin = bounds().min,
// i in 0..cells[0] and so on, cells[a] = ceil(box size / h) so that it covers the box.
struct MarchingLattice {
  Vec3 origin = Vec3::Zero();
  double h = 0;
  std::array<long, 3> cells{0, 0, 0};
};

// NoSurfaceError for an invalid box, InvalidInputError when a side needs more than 2^19 cells.
MarchingLattice make_marching_lattice(const Field& field, double cell_size);

const char* to_string(Traversal traversal);
const char* to_string(FaceAmbiguity rule);

}  // namespace cdp
