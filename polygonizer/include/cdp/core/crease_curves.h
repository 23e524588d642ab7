// The creases of a CSG surface as polylines: every curve where two pieces of a min/max/abs
// field (Field::pieces) meet on the surface, traced from crossings of a grid, ending at corners
// (where a third piece meets them) or closing on themselves. The exact creases the sharp-feature
// measures compare a mesh with, and what crease-aware meshing will start from.
#pragma once

#include <cdp/core/cancel.h>
#include <cdp/core/crease.h>
#include <cdp/core/field.h>
#include <cdp/core/progress.h>
#include <cdp/core/surface_seeds.h>

#include <array>
#include <cstdint>
#include <vector>

namespace cdp {

struct CreaseTracingOptions {
  // Grid cells along the box's longest side whose sign changes are searched for creases: a
  // crease passing within about one cell of a crossed grid edge is found (one whose whole length
  // fits between crossings, shorter than about a cell, can be missed).
  int resolution = 32;
  // Step along a crease: at most max_spacing, shortened (down to min_spacing) so that the
  // crease's tangent turns by at most max_turn radians a step. Non-positive spacings: 0.02 and
  // 0.0005 of the box diagonal.
  double max_spacing = 0;
  double min_spacing = 0;
  // The shortest step, where shorter than min_spacing (which also sets how near corners and
  // crossings are taken for one): a crease turning faster than max_turn allows at min_spacing is
  // followed by chords of that step. Non-positive: min_spacing.
  double min_step = 0;
  double max_turn = 0.1;
  // The largest number of points of all polylines together (a bound on the work).
  std::size_t max_points = 1'000'000;
  CreaseOptions newton;  // the projection onto the crease at each step
  // The grid of F over the field's bounds at `resolution` (sample_seed_grid), where the caller
  // has sampled it already (the adaptive polygonizer's seed grid): its crossings are searched
  // instead of those of a grid sampled again. Must outlive the call.
  const SeedGrid* grid = nullptr;
  // Polled at every crossing of the grid looked at, every corner and every step along a crease
  // (cancel.h): the tracing then ends with CancelledError. Must outlive the call.
  const CancelToken* cancel = nullptr;
  // Called now and then with the share of the grid's crossings looked at.
  ProgressCallback progress;
};

struct CreaseCurve {
  std::vector<Vec3> points;  // on both pieces to within the Newton tolerance
  bool closed = false;       // a loop: the last point connects back to the first
  // For an open curve, whether each end is a corner (three pieces meet there) rather than a
  // place where tracing stopped (a crease that fades out: the two pieces become tangent).
  bool starts_at_corner = false, ends_at_corner = false;
  // The branches (Field::piece) of the two pieces that meet along it.
  std::array<std::vector<std::uint8_t>, 2> pieces;
  // Where the crease fades into a switch that another branch hides (a box's edge entering a
  // smooth union's blend: past it the two pieces are one function), the curve goes on along the
  // switch of the one branch point where the pieces differ (project_to_seam), up to where the
  // crease comes back or a corner: that branch point, or -1 for a curve that is a crease
  // throughout. Such a seam bounds the two pieces' patches like a crease, without a bend.
  int seam_branch = -1;
};

struct CreaseTracingResult {
  std::vector<CreaseCurve> curves;
  std::vector<Vec3> corners;  // every corner once
  std::size_t stops = 0;      // curve ends that are not corners (tangent pieces, failed projections)
  std::size_t duplicates = 0;  // curves dropped as the same crease traced twice
};

// Every crease of `field` as polylines on both pieces (see the top of this file).
// \return the curves and corners; none for a field that reports no pieces (a smooth model).
// \throw InvalidInputError for a resolution below 2 or a seed grid of more than 2^26 nodes.
// \throw NoSurfaceError as sample_seed_grid (a box that is not valid, NaN next to the inside).
// \throw LimitExceededError past max_points.
// \throw what the field's evaluations throw.
CreaseTracingResult trace_creases(const Field& field, const CreaseTracingOptions& options = {});

}  // namespace cdp
