// The checks stage of a run: the last line of defence against a wrong mesh returned without an
// error, and the quality bounds polygonize_adaptive holds a smooth surface's mesh to.
#pragma once

#include "edge_length.h"
#include "missed_necks.h"

#include <cdp/core/cancel.h>
#include <cdp/core/errors.h>
#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace cdp::adaptive {

// The quality bounds on a smooth surface's mesh (see missed_bounds): a smallest angle of at least
// kBoundMinDegrees, at most kBoundShareUnder30 of the triangles with one under 30 degrees, a
// mean longest/shortest edge of at most kBoundMeanEdgeRatio. The last is also the repair's aim
// (QualityOptions::aim_mean_edge_ratio): its relaxation searches its moves where its plain
// sweeps leave the mean over it.
inline constexpr double kBoundMinDegrees = 20;
inline constexpr double kBoundShareUnder30 = 0.01;
inline constexpr double kBoundMeanEdgeRatio = 1.25;

// A point in the polygonizer's error messages: "(x, y, z)", six significant digits.
std::string describe_point(const Vec3& p);

// The tracker's own output must be closed, oriented and manifold, each seed must have grown one
// component of its own (a front that merged across a gap into another sheet joins two), and
// (unless `check_intersections` is off) no two triangles may intersect (fronts that crossed each
// other). (A test of triangles against the vertex normals was tried and dropped: the MPU
// models' correct meshes have triangles whose face turns more than 120 degrees from a noisy
// vertex normal.) `threads` as AdaptiveOptions::threads. `sealed` (optional, one flag per
// triangle): triangles known apart from one another (blocks' triangles, sealed_triangles), whose
// pairs are not tested.
// \return the mesh's components (== seeds).
// \throw NoSurfaceError naming the place of the first failure.
// \throw CancelledError when `cancel` is set during the intersection test.
// With `field`, a mesh that intersects itself where two sheets of the surface lie closer than the
// edges there (sheets_apart) says so, and their distance goes to `sheets_gap`.
std::size_t check_mesh(const Mesh& mesh, std::size_t seeds, bool check_intersections, int threads,
                       const CancelToken& cancel, const std::vector<char>* sealed = nullptr, const Field* field = nullptr,
                       double min_edge = 0, std::optional<double>* sheets_gap = nullptr);

// A neck or tunnel a front stepped over (check_necks). A NoSurfaceError that the crease-aware
// meshing does not fall back from: the recoveries zone the neck instead (Run::zone_missed_necks).
struct MissedNeckError : NoSurfaceError {
  using NoSurfaceError::NoSurfaceError;
};

// Necks and tunnels a front stepped over (missed_necks.h, from the tracker's `critical_starts`):
// a handle too few, each component whole, which check_mesh passes. Searched on the tracker's
// closed mesh before the repair, which neither makes nor removes handles, so that such a mesh
// fails before the repair and the checks work on it (the crowd of 200 blobs at factor 1: 12.1 s
// to 10.1 s). `necks` receives the search, before the error when there is one (the recoveries
// zone the necks it names). `min_edge` only words the message.
// \throw MissedNeckError naming the place.
void check_necks(const Field& field, const Mesh& mesh, std::span<const CriticalStart> critical_starts,
                 double min_edge, NeckSearch& necks);

// Two of the mesh's `components` that face each other across the solid where the surface joins
// them (surface_gaps.h): a front that crossed a neck narrower than its edges and closed on each
// side of it, which check_mesh passes.
// \throw NoSurfaceError naming the place.
void check_components_apart(const Field& field, const Mesh& mesh, std::size_t components);

// A triangle whose middle lies s off the surface with its longest edge L stands on a bend of
// radius about L^2 / (6 s) (the middle of an equilateral triangle inscribed in a sphere of radius
// r lies L^2 / (6 r) inside it). Where L is more than this many times the edge the sizing asks
// for at that radius, the triangle cuts across a bend finer than its corners saw. On the numpy
// functions of python/README.md (a torus, a twisted ellipsoid, blobs, a rounded box) at factors
// 3 and 8, tracked alone and in blocks, the largest ratio was 1.64 wherever the mesh followed the
// surface; blocks in lockstep cut a rounded box's fillets at factor 8 at ratios up to 7.5 (before
// the seams between blocks were graded: grade_along, blocks.cpp).
inline constexpr double kBendChordRatio = 3;
// Triangles per call of the field in check_bends_kept: a Python function's arrays of their
// stencils (seven points each) stay near 100 kB, within the allocator's heap.
inline constexpr std::size_t kBendCheckBatch = 2048;

// The mesh's triangles against the bends under them (kBendChordRatio), their middles' distances
// measured in batched calls of the field. Run after blocks meshed in lockstep (a function
// whose calls cost more than their points), where the repair of the band around their seams cut
// a rounded box's fillets with nothing else to say so: the run then tracks the surface alone.
// \throw NoSurfaceError naming the worst triangle's place.
void check_bends_kept(const Field& field, const Mesh& mesh, const Sizing& sizing);

// The smallest angle of the mesh's triangles, in degrees (180 for no triangle).
double min_angle_degrees(const Mesh& mesh);

// The triangles whose smallest angle is under `bound` (radians, under 60 degrees). `threads` as
// AdaptiveOptions::threads (the same count on any number).
std::size_t triangles_under(const Mesh& mesh, double bound, int threads = 1);

// The mean over the triangles of the longest edge over the shortest (infinite with a zero-length
// edge), the relaxation's measure (QualityOptions::aim_mean_edge_ratio). Summed in shares of
// 2^16 triangles, in order: the same number on any number of `threads`.
double mean_edge_ratio(const Mesh& mesh, int threads = 1);

// How many of the quality bounds `mesh` misses (see kBoundMinDegrees): a smallest angle under
// kBoundMinDegrees, more than kBoundShareUnder30 of the triangles with one under 30 degrees, a
// mean longest/shortest edge over kBoundMeanEdgeRatio, triangles farther from the surface than
// the tolerance (`over_tolerance`, the repair's dense measurement). A zero-area triangle counts
// as one under kBoundMinDegrees.
int missed_bounds(const Mesh& mesh, std::size_t over_tolerance);

}  // namespace cdp::adaptive
