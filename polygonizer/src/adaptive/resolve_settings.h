// The first step of every run: the caller's options with every default resolved.
#pragma once

#include "tracker.h"

#include <cdp/core/adaptive_polygonizer.h>

#include <optional>

namespace cdp::adaptive {

// The options with every default resolved: the sizing (the tolerance's share, the edge bounds
// that follow the diagonal and the tolerance), the bounds on triangles, steps and searches.
// \pre field.bounds() is the box to mesh.
// \throw NoSurfaceError when the field has no valid bounding box.
// \throw InvalidInputError for a NaN or non-finite tolerance or edge length, min_edge above
//        max_edge, a factor that is not a positive number, collision_factor outside [0.5, 3],
//        seed_resolution below 2, negative threads.
Settings resolve_settings(const Field& field, const AdaptiveOptions& options);

// The tolerance the caller asked for (the sizing may use a share of it): 1e-3 of the diagonal
// where none is given.
double requested_tolerance(const AdaptiveOptions& options, const Settings& settings);

// Whether a run may be made again after it failed or missed a bound: not after a run stopped
// by the caller's own bounds (max_triangles, max_steps, max_search_visits: a run made again with
// shorter edges would pass them sooner), nor in paper mode (the algorithm as printed, whatever it gives).
bool remeshing_allowed(const AdaptiveOptions& options);

// The min_edge a run that failed is meshed again with (kRuns' lowered_min_edge,
// adaptive_polygonizer.cpp) where the surface bends more tightly than the default min_edge lets
// edges follow: kBendEdgeShare of the tightest radius of curvature the run met, not below
// kLowestMinEdge of the diagonal. None where the caller set min_edge (a bound the caller set is
// kept), where remeshing_allowed says no, or where the radius is not under min_edge or is below
// kLowestBendShare of that lowest edge (a crease or a singular point, not a bend to follow).
std::optional<double> lowered_min_edge(const Field& field, const AdaptiveOptions& options, double tightest_radius);

// The min_edge a tolerance-mode mesh with triangles beyond the tolerance is meshed again with
// (kRuns' for_tolerance): where the chord the sizing allows round the tightest bend the run met
// (chord_for_deviation) is under twice min_edge, the refinement cannot halve edges that long
// there; half that chord, not below kLowestMinEdge of the diagonal. None where the caller set
// min_edge, where remeshing_allowed says no, outside tolerance mode, or where the radius is below
// kLowestBendShare of that lowest edge (a crease or a singular point).
std::optional<double> min_edge_for_tolerance(const Field& field, const AdaptiveOptions& options, double tightest_radius);

// The options a run that failed where two sheets of the surface lie `gap` apart, closer than its
// edges (a shell, a plate: Tracker::sheets_closer_than_edges), is meshed again with (kRuns'
// thin_sheets): max_edge twice the gap, and a seed grid whose cells are at most kSheetGridCells
// times it, so that its sign changes see both sheets and it measures their area. None where the
// caller set max_edge or min_edge, or where twice the gap is under min_edge (the caller lowers it).
std::optional<AdaptiveOptions> options_for_sheets(const Field& field, const AdaptiveOptions& options, double gap);

}  // namespace cdp::adaptive
