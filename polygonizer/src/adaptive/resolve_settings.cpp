// resolve_settings: the caller's AdaptiveOptions with every default resolved (the first step of a run).
#include "resolve_settings.h"

#include "edge_length.h"

#include <cdp/core/errors.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace cdp::adaptive {
namespace {

// Variant::Improved with a tolerance sizes edges for a sagitta of this share of eps, and the
// refinement of quality.h splits what still exceeds eps. A triangle deviates more than its
// edges (an equilateral one with edges of sagitta s bulges 4/3 s at its centre: circumradius
// l / sqrt(3) against l / 2), so the full eps leaves many triangles to split, and splits make
// uneven triangles (each split leaves a vertex of valence 4, which the relaxation cannot make
// equilateral without breaking the bound the split just met); a small share makes triangles no
// split would have needed. Measured on the torus (R = 1, r = 0.35) at eps = 1e-3 before the
// relaxation: shares 0.5, 0.7, 1.0 give 25.9k, 19.6k, 19.8k triangles with 57, 534, 3488 splits
// and mean edge ratios 1.22, 1.25, 1.47. With it, shares 0.7 / 0.65 / 0.6: the unit sphere at
// 1e-4 83.3k / 78.7k / 77.6k triangles, 12.7k / 8.1k / 4.9k splits, ratios 1.289 / 1.237 / 1.199;
// the torus at 1e-3 19.5k / 20.5k / 21.9k, 1.168 / 1.157 / 1.145; the bunny VIS-800 at 3e-5
// 74.0k / 77.2k / 82.5k, 1.180 / 1.169 / 1.161. 0.65 is the largest share that keeps every
// measured case under the mean ratio of 1.25 (the quality bounds), at -6 % to +5 % triangles.
constexpr double kToleranceSizingShare = 0.65;
// SizingMode::Chord's edges turn the normal by at most this many radians (Sizing::max_turn): the
// paper's factor 1 where the chord sizing asks for longer edges. Without it blobs19 of the
// topology sweep at a chord deviation of 1e-3 of the diagonal kept a triangle of 10.5 degrees
// (2280 triangles; 28.2 degrees with it, and 23.0 / 26.4 with 0.7 / 0.5).
constexpr double kChordMaxTurn = 1;

}  // namespace

Settings resolve_settings(const Field& field, const AdaptiveOptions& o) {
  const Box& box = field.bounds();
  if (!box.valid()) throw NoSurfaceError("adaptive: the field has no valid bounding box");
  const double diag = box.diagonal();
  const auto positive_or_default = [](double v, double fallback) { return v > 0 ? v : fallback; };
  Settings s;
  s.diagonal = diag;
  s.sizing.mode = o.sizing;
  s.sizing.factor = o.factor;
  // A NaN would otherwise pass for "not given" below (positive_or_default).
  if (std::isnan(o.tolerance)) throw InvalidInputError("adaptive: the tolerance must be a number, not nan");
  if (std::isnan(o.min_edge)) throw InvalidInputError("adaptive: min_edge must be a number, not nan");
  if (std::isnan(o.max_edge)) throw InvalidInputError("adaptive: max_edge must be a number, not nan");
  s.sizing.tolerance = positive_or_default(o.tolerance, 1e-3 * diag);
  if (o.variant == Variant::Improved && o.sizing == SizingMode::Tolerance) s.sizing.tolerance *= kToleranceSizingShare;
  // The chord sizing asks for chords longer than the radius of curvature where eps exceeds r / 8;
  // Tolerance's refinement splits what that leaves beyond eps, and Chord, which measures
  // nothing, keeps its edges to the turn of the paper's factor 1 instead (kChordMaxTurn).
  if (o.variant == Variant::Improved && o.sizing == SizingMode::Chord) s.sizing.max_turn = kChordMaxTurn;
  s.grading = o.variant == Variant::Improved;
  s.side_points = o.variant == Variant::Improved && !field.has_pieces();
  // A black box its caller calls smooth (Field::smooth) has bends, not creases: one tighter than
  // the differences' step is meshed across as with creases: ignore rather than refused.
  s.stop_at_kink = o.variant == Variant::Improved && o.creases == CreaseHandling::Follow && field.derivative_step() &&
                   !field.smooth();
  // The default min_edge matches the default tolerance (1e-3 of the diagonal); a smaller
  // tolerance asks for edges shorter as its square root (the sagitta grows as the edge
  // squared), and Variant::Improved lowers the default with it so that the clamp does not
  // break the distance bound a tolerance promises, nor coarsen the sizing a chord asks for.
  double min_edge_default = 2e-3 * diag;
  if (o.variant == Variant::Improved && o.sizing != SizingMode::Factor && o.tolerance > 0 && o.tolerance < 1e-3 * diag)
    min_edge_default *= std::sqrt(o.tolerance / (1e-3 * diag));
  s.sizing.min_edge = positive_or_default(o.min_edge, min_edge_default);
  s.sizing.max_edge = positive_or_default(o.max_edge, 0.1 * diag);
  s.hash_cell = s.sizing.max_edge;  // refined from the seed crossings once they are known
  if (o.sizing == SizingMode::Factor && !(std::isfinite(o.factor) && o.factor > 0))
    throw InvalidInputError("adaptive: the factor must be a positive number, not " + std::to_string(o.factor));
  if (!std::isfinite(s.sizing.tolerance) || !std::isfinite(s.sizing.min_edge) || !std::isfinite(s.sizing.max_edge))
    throw InvalidInputError("adaptive: tolerance and edge lengths must be finite");
  if (s.sizing.min_edge > s.sizing.max_edge)
    throw InvalidInputError("adaptive: min_edge (" + std::to_string(s.sizing.min_edge) + ") exceeds max_edge (" +
                            std::to_string(s.sizing.max_edge) + ")");
  if (!(o.collision_factor >= 0.5 && o.collision_factor <= 3))
    throw InvalidInputError("adaptive: collision_factor must lie in [0.5, 3]");
  if (o.seed_resolution < 2) throw InvalidInputError("adaptive: seed_resolution must be at least 2");
  if (o.threads < 0) throw InvalidInputError("adaptive: threads must be 0 (all cores) or positive");
  s.rule = o.triangle_count;
  s.collision_factor = o.collision_factor;
  s.curvature_properties = o.curvature_properties;
  const Vec3 e = box.size();
  const double box_area = 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  const double tri_area = std::sqrt(3.0) / 4 * s.sizing.min_edge * s.sizing.min_edge;
  const double derived = std::min(5e7, std::max(1e4, 20 * box_area / tri_area));
  s.max_triangles = o.max_triangles > 0 ? o.max_triangles : static_cast<std::size_t>(derived);
  s.max_steps = o.max_steps > 0 ? o.max_steps : 4 * s.max_triangles + 10000;
  s.search_visits_per_step = o.max_search_visits > 0 ? o.max_search_visits : kSearchVisitsPerStep;
  s.callers_search_bound = o.max_search_visits > 0;
  s.cancel = o.cancel;
  return s;
}

double requested_tolerance(const AdaptiveOptions& o, const Settings& s) {
  return o.tolerance > 0 ? o.tolerance : 1e-3 * s.diagonal;
}

bool remeshing_allowed(const AdaptiveOptions& o) {
  return o.variant == Variant::Improved && o.max_triangles == 0 && o.max_steps == 0 && o.max_search_visits == 0;
}

namespace {

// The perturbed Barth sextic clipped by a ball (its necks bend with a radius of 0.0083, the
// default min_edge is 0.0145) fails at factors 1-3 and meshes with min_edge 0.0021, a quarter of
// that radius, in 0.7-3.3 s. Not below kLowestMinEdge of the diagonal, a tenth of the default; a
// bend down to kLowestBendShare of that edge is meshed with it (a crowd of 200 Wyvill blobs, two
// of them joined by a neck 0.006 wide that bends with a radius of 0.0012, meshes with min_edge
// 0.0018 at factors 1 and 2 and tolerance 1e-2, and failed at all three); a tighter radius is a
// crease or a singular point, not a bend to follow.
constexpr double kBendEdgeShare = 0.25;
constexpr double kLowestMinEdge = 2e-4;
constexpr double kLowestBendShare = 0.5;

// What both ways of lowering min_edge for a bend start from: the run's settings and the lowest
// min_edge they may go to. None where the caller set min_edge, where remeshing_allowed says no, or
// where the radius is below kLowestBendShare of that lowest edge.
struct BendLowering {
  Settings settings;
  double lowest;
};
std::optional<BendLowering> bend_lowering(const Field& field, const AdaptiveOptions& o, double tightest_radius) {
  if (!remeshing_allowed(o) || o.min_edge > 0) return std::nullopt;
  BendLowering b{resolve_settings(field, o), 0};
  b.lowest = kLowestMinEdge * b.settings.diagonal;
  if (!(tightest_radius >= kLowestBendShare * b.lowest)) return std::nullopt;
  return b;
}

}  // namespace

std::optional<double> lowered_min_edge(const Field& field, const AdaptiveOptions& o, double tightest_radius) {
  const std::optional<BendLowering> b = bend_lowering(field, o, tightest_radius);
  if (!b || !(tightest_radius < b->settings.sizing.min_edge)) return std::nullopt;
  return std::max(kBendEdgeShare * tightest_radius, b->lowest);
}

std::optional<double> min_edge_for_tolerance(const Field& field, const AdaptiveOptions& o, double tightest_radius) {
  if (o.sizing != SizingMode::Tolerance) return std::nullopt;
  const std::optional<BendLowering> b = bend_lowering(field, o, tightest_radius);
  if (!b) return std::nullopt;
  const Sizing& sizing = b->settings.sizing;
  const double chord = chord_for_deviation(tightest_radius, sizing.tolerance);
  const double lowered = std::max(0.5 * chord, b->lowest);
  if (!(chord < 2 * sizing.min_edge) || !(lowered < sizing.min_edge)) return std::nullopt;
  return lowered;
}

std::optional<AdaptiveOptions> options_for_sheets(const Field& field, const AdaptiveOptions& o, double gap) {
  if (!remeshing_allowed(o) || o.max_edge > 0 || o.min_edge > 0 || !(gap > 0) || !std::isfinite(gap)) return std::nullopt;
  const Settings s = resolve_settings(field, o);
  if (!(2 * gap >= s.sizing.min_edge) || !(2 * gap < s.sizing.max_edge)) return std::nullopt;
  AdaptiveOptions again = o;
  again.max_edge = 2 * gap;
  const double side = field.bounds().size().maxCoeff();
  again.seed_resolution = std::max(o.seed_resolution, static_cast<int>(std::ceil(side / (kSheetGridCells * gap))));
  return again;
}

}  // namespace cdp::adaptive
