// The adaptive polygonizer's choices, as scoped enums: the sizing, the triangle count, the
// variant and the crease handling (AdaptiveOptions, adaptive_polygonizer.h). Apart from the
// options so that the typed report (adaptive_report.h) and the internal stages can name them.
#pragma once

namespace cdp {

// How the target edge length follows the minimum radius of curvature r at a point.
enum class SizingMode {
  Factor,     // the paper: l = r / factor
  Tolerance,  // chord deviation: l = 2 sqrt(2 r eps - eps^2), so the chord sags at most eps
  // The sizing of Tolerance aimed at eps itself, without its bound: nothing is measured or
  // refined, so the mesh's distance to the surface is not bounded (a triangle sags about 4/3
  // of its edges' eps, more where the curvature changes along it); in Variant::Improved no edge
  // longer than min_edge turns the normal by more than a radian. In Variant::Paper it is the
  // tolerance, the same mesh. What it costs and gains against Tolerance and Factor:
  // bench/README.md, "Measurements behind the options".
  Chord,
};

// How many triangles the expansion of a front point with front angle theta produces.
enum class TriangleCountRule {
  // The paper's formula as printed, n = floor(3 theta / pi); n <= 1 closes the angle.
  PaperFloor,
  // Hartmann (1998): n = trunc(3 theta / pi) + 1; n - 1 when theta / n < 0.8 and n > 1; n = 2
  // when n = 1, theta > 0.8 and the two neighbours are farther apart than 1.2 delta.
  Hartmann,
};

// Which algorithm runs.
enum class Variant {
  // The paper's tracker with this project's additions for the triangles' shape and the
  // tolerance: the grading of new points' edge lengths, the local repair of triangles whose
  // smallest angle is under 30 degrees (edge flips, tangential vertex moves back onto the surface,
  // collapses of needles' short edges; src/adaptive/quality.h), and with SizingMode::Tolerance a
  // sizing margin plus splits of triangles sampled beyond the tolerance, so that it bounds the
  // distance between mesh and surface. A smooth surface's mesh that still misses the quality
  // bounds (a triangle under 20 degrees, more than 1% under 30, a mean longest/shortest edge
  // over 1.25, a triangle beyond the tolerance) is made once more with the fronts looking
  // ahead at the targets of front points nearby, and the mesh that misses fewer is kept (stats
  // "quality_rerun", "quality_rerun_kept", "look_ahead"; not when max_triangles or max_steps is set).
  Improved,
  // The algorithm as printed (Figure 6 with Hartmann's triangle count, see triangle_count),
  // none of the additions above: what the paper's method alone gives.
  Paper,
};

// What the adaptive method does with the creases and corners of a CSG field (one whose model
// reports its pieces: Field::pieces; other models are smooth and have none).
enum class CreaseHandling {
  // Trace the creases first and mesh each piece's patches from them (src/adaptive/
  // crease_patches.h): mesh edges run along the creases, and crease vertices lie on both pieces.
  // Where the creases cannot be laid out as patch boundaries, or a patch cannot be meshed, the
  // surface is meshed as if it were smooth (stats "creases.followed" says which). A field
  // without branch data whose derivatives are differences (Field::derivative_step: a Python
  // function) has no creases to trace: the run stops at the first vertex placed on a crease or
  // corner of it, with an error naming the place (adaptive::BlackBoxKinkError).
  Follow,
  // Mesh across creases as across curvature (the paper's method; Variant::Paper always does).
  Ignore,
};

// The spellings of the options table, STATS.json and the Python keywords.
const char* to_string(SizingMode mode);
const char* to_string(CreaseHandling creases);
const char* to_string(TriangleCountRule rule);
const char* to_string(Variant variant);

}  // namespace cdp
