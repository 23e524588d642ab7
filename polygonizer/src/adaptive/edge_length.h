// Target edge length from the local minimum radius of curvature (paper section 3), in the
// paper's factor mode or as a chord-deviation tolerance, clamped to [min_edge, max_edge].
#pragma once

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/field.h>

namespace cdp::adaptive {

struct Sizing {
  SizingMode mode = SizingMode::Factor;
  double factor = 2;
  double tolerance = 0;
  double min_edge = 0;
  double max_edge = 0;
  // Positive: no edge longer than min_radius times this, the largest turn of the normal along
  // one edge in radians (1: the paper's factor 1). A tolerance far coarser than the curvature
  // (eps above r / 8) otherwise asks for chords longer than the radius: edges of 0.035 around
  // the needle's tips, 0.04 thick, at eps = 1e-2. Set by the careful run (Settings::anticipate)
  // and, from the start, by SizingMode::Chord in Variant::Improved (kChordMaxTurn).
  double max_turn = 0;
};

// r_min may be +infinity (flat point): the result is then max_edge.
double edge_length(const Sizing& sizing, double min_radius);

// The edges may grow by this share of the distance from a C1 seam whose other side curves more
// (a rounded box's flat face meeting its rounded edge, where the curvature jumps from 0 to
// 1 / radius), so that edges coming over the flat side shorten before they reach the seam, as
// the tracker's look-ahead grades them towards a finer front (kLookAheadGradation).
inline constexpr double kSeamGradation = 0.4;

// The target edge length at p (on the surface of `field`) that the C1 seams near it ask for
// (Field::smooth_sides): for each, the length the curvature beyond it asks for, plus
// kSeamGradation times its distance; the smallest, and infinity where none is nearer than
// `own` / kSeamGradation (`own`: the length p's own curvature asks for, which a seam farther away
// cannot undercut). With `branch`, the seams of that piece, their far side evaluated where `at`
// says (Field::smooth_sides).
double seam_edge_length(const Field& field, const Sizing& sizing, const Vec3& p, double own,
                        const std::vector<std::uint8_t>& branch = {},
                        Field::SeamSideAt at = Field::SeamSideAt::Point);

// Longest chord of a circle of radius r whose sagitta (r - sqrt(r^2 - l^2/4)) is at most eps.
double chord_for_deviation(double r, double eps);

}  // namespace cdp::adaptive
