#include "crease_patches.h"
#include "spatial_hash.h"
#include "../parallel.h"
#include "../surface_passes.h"
#include "../union_find.h"

#include <cdp/core/crease.h>
#include <cdp/core/curvature.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

namespace cdp::adaptive {

namespace {

using Branch = std::vector<std::uint8_t>;

// A curve end is the corner it names when within this share of the diagonal (trace_creases
// merges corners found from several curves within its min_spacing, 0.0005 of the diagonal).
constexpr double kCornerMatch = 5e-4;
// The side test of orient_darts steps this share of min_edge off the crease: far beyond the
// Newton tolerance, far inside the patch next to a crease sample.
constexpr double kSideProbe = 0.05;
// ... and looks this share of that step either way along the piece's normal for the field's
// sign change that shows the surface passes there: far less than the step, where the gyroid
// ball's sheets meet its sphere at a few degrees and leave a wedge thinner than a tenth of it.
constexpr double kSideDepth = 1e-3;

// A piece as a field of its own: the smooth function with the piece's branches fixed. Its zero
// set continues past the crease (where the CSG field takes another piece), so the fronts of its
// patches walk on a smooth surface, and the patch's boundary keeps them inside.
class PieceField final : public Field {
 public:
  PieceField(const Field& field, Branch branch) : field_(field), branch_(std::move(branch)) {
    set_bounds(field.bounds());
  }
  std::string type_name() const override { return field_.type_name() + " piece"; }
  bool thread_safe() const override { return field_.thread_safe(); }

 protected:
  double eval_value(const Vec3& p) const override { return field_.piece(p, branch_).value; }
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override {
    const FieldPiece q = field_.piece(p, branch_);
    gradient = q.gradient;
    return q.value;
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override {
    const FieldPiece q = field_.piece(p, branch_);
    gradient = q.gradient;
    hessian = q.hessian;
    return q.value;
  }
  // The seams of this piece's own face, where the field itself may take the other's branch (a
  // piece has one branch, its own).
  std::vector<SmoothSide> eval_smooth_sides(const Vec3& p, double radius, const Branch&, SeamSideAt at) const override {
    return field_.smooth_sides(p, radius, branch_, at);
  }

 private:
  const Field& field_;
  Branch branch_;
};

// Vertices on creases, shared by the pieces that meet there.
struct CreaseVertices {
  std::vector<Vec3> points;
  int add(const Vec3& p) {
    points.push_back(p);
    return static_cast<int>(points.size()) - 1;
  }
};

struct LaidCurve {
  std::vector<int> vertices;  // along the traced direction; a loop does not repeat its first
  bool closed = false;
  int start_corner = -1, end_corner = -1;  // indices into the corner list (open curves)
  std::array<Branch, 2> pieces;
  int seam_branch = -1;  // CreaseCurve::seam_branch
  // The largest distance between an edge's midpoint and the crease (the chords' sagitta): how
  // far the patch's polygonal boundary strays from the patch.
  double sagitta = 0;
};

// One side of a crease as a patch boundary: the curve's vertices in the order that has the
// piece's patch on the left seen from outside.
struct Dart {
  int curve = -1, side = -1;
  std::vector<int> vertices;
  int from = -1, to = -1;  // corners (open curves)
};

// How far apart parts of the crease network that are not neighbours along it may come before
// they bound the spacing: another part is a point whose distance along the creases (on the
// same curve, or through a corner both curves end at) is over kOtherPart times its distance in
// space. Two creases that pass close by each other bound a strip of patch between them, and
// crease edges longer than the strip is wide make chords that cut across the strip, from both
// sides (the gyroid ball at factor 1 came out with edges of four triangles there).
constexpr double kOtherPart = 2;
// Crease edges are at most this share of the distance to another part: two edges across the
// strip between them, so that its fronts have room for a point inside it (with one, the gyroid
// ball at factor 1 still had both sides join the two creases by the same edge).
constexpr double kFeatureShare = 0.5;

// For every traced point of every curve: the distance to the nearest other part of the creases
// (infinity when none is within `reach`).
std::vector<std::vector<double>> crease_feature_size(const CreaseTracingResult& creases, std::span<const int> start_corner,
                                                     std::span<const int> end_corner, double reach) {
  struct Where {
    std::size_t curve, index;
  };
  std::vector<Where> where;
  // Arc length at each point, and each curve's length (a loop's with its closing segment).
  std::vector<std::vector<double>> arc(creases.curves.size()), out(creases.curves.size());
  std::vector<double> length(creases.curves.size());
  SpatialHash hash(reach);
  for (std::size_t c = 0; c < creases.curves.size(); ++c) {
    const std::vector<Vec3>& P = creases.curves[c].points;
    arc[c].assign(P.size(), 0.0);
    for (std::size_t i = 1; i < P.size(); ++i) arc[c][i] = arc[c][i - 1] + (P[i] - P[i - 1]).norm();
    length[c] = arc[c].back() + (creases.curves[c].closed ? (P.back() - P.front()).norm() : 0.0);
    out[c].assign(P.size(), std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < P.size(); ++i) {
      hash.insert(static_cast<int>(where.size()), P[i]);
      where.push_back({c, i});
    }
  }
  // Distance along the creases from (c, i) to (d, j): along one curve (either way round a
  // loop), or through a corner the two curves share; infinity otherwise.
  const auto along = [&](std::size_t c, std::size_t i, std::size_t d, std::size_t j) {
    const auto& ac = arc[c];
    double best = std::numeric_limits<double>::infinity();
    if (c == d) {
      best = std::abs(ac[i] - ac[j]);
      if (creases.curves[c].closed) best = std::min(best, length[c] - best);
    }
    const double to_start_c = ac[i], to_end_c = ac.back() - ac[i];
    const double to_start_d = arc[d][j], to_end_d = arc[d].back() - arc[d][j];
    for (const auto& [kc, lc] : {std::pair{start_corner[c], to_start_c}, std::pair{end_corner[c], to_end_c}})
      for (const auto& [kd, ld] : {std::pair{start_corner[d], to_start_d}, std::pair{end_corner[d], to_end_d}})
        if (kc >= 0 && kc == kd) best = std::min(best, lc + ld);
    return best;
  };
  for (const Where& w : where) {
    const Vec3& p = creases.curves[w.curve].points[w.index];
    double& best = out[w.curve][w.index];
    hash.for_each_near(p, reach, [&](int id) {
      const Where& o = where[static_cast<std::size_t>(id)];
      const double d = (creases.curves[o.curve].points[o.index] - p).norm();
      if (d >= best || d > reach) return;
      if (along(w.curve, w.index, o.curve, o.index) > kOtherPart * d) best = d;
    });
  }
  return out;
}

double piece_edge_length(const Field& field, const Sizing& sizing, const Vec3& p, const Branch& b) {
  const FieldPiece q = field.piece(p, b);
  return edge_length(sizing, curvature_from_derivatives(q.gradient, q.hessian).min_radius);
}

// The crease as vertices about one target edge length apart, where the target at a point is the
// smallest the sizing gives for either side's curvature and for the crease's own (a circle
// through three consecutive traced points): the fronts of both sides start from these edges, so
// they must suit both. Every vertex is moved onto the crease (both pieces to the Newton
// tolerance). The ends of an open curve are its corners' vertices.
LaidCurve resample_curve(const Field& field, const CreaseCurve& curve, std::span<const double> feature_size,
                         const Sizing& sizing, std::span<const int> corner_vertex, std::span<const Vec3> corners,
                         double diagonal, CreaseVertices& cv) {
  LaidCurve out;
  out.closed = curve.closed;
  out.pieces = curve.pieces;
  out.seam_branch = curve.seam_branch;
  const std::vector<Vec3>& P = curve.points;
  const std::size_t n = P.size();
  if (n < 2) throw CreaseLayoutError("adaptive: a crease traced as a single point near " + format_point(P.at(0)));
  if (!curve.closed) {
    const auto match = [&](const Vec3& p) {
      for (std::size_t i = 0; i < corners.size(); ++i)
        if ((corners[i] - p).norm() <= kCornerMatch * diagonal) return static_cast<int>(i);
      throw CreaseLayoutError("adaptive: a crease ends without a corner near " + format_point(p) +
                              " (its pieces become tangent there)");
    };
    if (!curve.starts_at_corner || !curve.ends_at_corner)
      throw CreaseLayoutError("adaptive: a crease ends without a corner near " +
                              format_point(curve.starts_at_corner ? P.back() : P.front()) +
                              " (its pieces become tangent there)");
    out.start_corner = match(P.front());
    out.end_corner = match(P.back());
    if (out.start_corner == out.end_corner && n < 4)
      throw CreaseLayoutError("adaptive: a crease returns to its corner at once near " + format_point(P.front()));
  }
  // Segments of the polyline (a loop's last one closes it) and the target at each point.
  const std::size_t segments = curve.closed ? n : n - 1;
  const auto at = [&](std::size_t i) -> const Vec3& { return P[i % n]; };
  std::vector<double> h(n);
  for (std::size_t i = 0; i < n; ++i) {
    double len = std::min(piece_edge_length(field, sizing, P[i], curve.pieces[0]),
                          piece_edge_length(field, sizing, P[i], curve.pieces[1]));
    // As the patches' fronts will (Tracker::Placed), each on its own face: at the crease the field
    // takes either face's branch, and with it sees only that face's seams. The far side is taken
    // where it begins: continued to the crease, a fillet 0.1-0.15 away looked seven times flatter
    // (a box's edge beside a crossing filleted hole kept edges of 0.3 there beside the fillet's
    // 0.03, and the strip of face between them had triangles of 17-18 degrees). The fronts keep
    // the far side continued to their point: taken where it begins, their targets left fans of
    // slivers on the face of a box with a filleted hole at tolerance 5e-2 (0.8 degrees).
    for (const Branch& piece : curve.pieces)
      len = std::min(len, seam_edge_length(field, sizing, P[i], len, piece, Field::SeamSideAt::Seam));
    const bool interior = curve.closed || (i > 0 && i + 1 < n);
    if (interior) {
      const Vec3 a = P[i] - at(i + n - 1), b = at(i + 1) - P[i];
      const double turn = std::atan2(a.cross(b).norm(), a.dot(b));
      const double radius = turn > 0 ? 0.5 * (a.norm() + b.norm()) / turn : std::numeric_limits<double>::infinity();
      len = std::min(len, edge_length(sizing, radius));
    }
    h[i] = std::max(sizing.min_edge, std::min(len, kFeatureShare * feature_size[i]));
  }
  // Equal steps of the integral of ds / h: edges follow the target and change smoothly.
  std::vector<double> cumulative(segments + 1, 0.0);
  for (std::size_t j = 0; j < segments; ++j) {
    const double len = (at(j + 1) - at(j)).norm();
    cumulative[j + 1] = cumulative[j] + len * 0.5 * (1 / h[j] + 1 / h[(j + 1) % n]);
  }
  const double total = cumulative.back();
  const std::size_t edges =
      std::max(curve.closed ? kMinLoopEdges : kMinOpenEdges, static_cast<std::size_t>(std::ceil(total - 1e-9)));
  const std::vector<Branch> two{curve.pieces[0], curve.pieces[1]};
  CreaseOptions co;
  co.tolerance = 1e-10 * diagonal;
  // Onto the crease; where it has faded into a seam, onto the switch there.
  const auto project = [&](const Vec3& guess) {
    CreaseProjection c = project_to_crease(field, guess, two, co);
    if (!c.ok() && curve.seam_branch >= 0)
      c = project_to_seam(field, guess, curve.pieces[0], static_cast<std::size_t>(curve.seam_branch), co);
    return c;
  };
  std::size_t j = 0;
  const std::size_t first = curve.closed ? 0 : 1;
  if (!curve.closed) out.vertices.push_back(corner_vertex[static_cast<std::size_t>(out.start_corner)]);
  for (std::size_t k = first; k < edges; ++k) {
    const double s = total * static_cast<double>(k) / static_cast<double>(edges);
    while (j + 1 < segments && cumulative[j + 1] < s) ++j;
    const double span = cumulative[j + 1] - cumulative[j];
    const double t = span > 0 ? std::clamp((s - cumulative[j]) / span, 0.0, 1.0) : 0.0;
    const Vec3 guess = at(j) + t * (at(j + 1) - at(j));
    if (k == 0) {
      out.vertices.push_back(cv.add(P[0]));  // a traced point: on the crease already
      continue;
    }
    const CreaseProjection c = project(guess);
    if (!c.ok() || (c.point - guess).norm() > 0.5 * std::max(h[j], h[(j + 1) % n]))
      throw CreaseVertexError("adaptive: a crease vertex could not be put on its crease near " + format_point(guess) +
                              " (" + to_string(c.status) + ")");
    out.vertices.push_back(cv.add(c.point));
  }
  if (!curve.closed) out.vertices.push_back(corner_vertex[static_cast<std::size_t>(out.end_corner)]);
  const std::size_t m = out.vertices.size();
  for (std::size_t k = 0; k + (curve.closed ? 0 : 1) < m; ++k) {
    const Vec3 mid = 0.5 * (cv.points[static_cast<std::size_t>(out.vertices[k])] +
                            cv.points[static_cast<std::size_t>(out.vertices[(k + 1) % m])]);
    const CreaseProjection c = project(mid);
    if (c.ok()) out.sagitta = std::max(out.sagitta, (c.point - mid).norm());
  }
  return out;
}

// The two darts of a laid curve. The side of each piece's patch is found next to a vertex in the
// middle of the curve: a point a little off the crease on the piece's own zero set, to the left
// of the crease's direction seen from the piece's outside, is in the piece's patch when the CSG
// field takes that piece there.
std::array<Dart, 2> orient_darts(const Field& field, const LaidCurve& c, int index, const CreaseVertices& cv,
                                 std::span<const Vec3> traced, double min_edge) {
  std::array<Dart, 2> out;
  const std::size_t m = c.vertices.size() / 2;  // interior for open curves (at least three vertices)
  Vec3 p = cv.points[static_cast<std::size_t>(c.vertices[m])];
  Vec3 along = cv.points[static_cast<std::size_t>(c.vertices[(m + 1) % c.vertices.size()])] -
               cv.points[static_cast<std::size_t>(c.vertices[m - (m > 0 ? 1 : 0)])];
  // On a seam the two pieces are one function and either side could be either's: the traced
  // point where they differ most instead. (The laid vertices may all lie on the seam: a box's
  // edge swallowed in its middle by a ball smoothly united with it, at factor 1, had its only
  // interior vertices there, and the sides came out the same.)
  if (c.seam_branch >= 0 && traced.size() >= 3) {
    const std::size_t n = traced.size();
    double widest = -1;
    std::size_t w = 0;
    for (std::size_t i = c.closed ? 0 : 1; i + (c.closed ? 0 : 1) < n; ++i) {
      const Vec3& q = traced[i];
      const double sine = field.piece(q, c.pieces[0]).gradient.normalized().cross(field.piece(q, c.pieces[1]).gradient.normalized()).norm();
      if (sine > widest) widest = sine, w = i;
    }
    p = traced[w];
    along = traced[(w + 1) % n] - traced[(w + n - 1) % n];
  }
  for (int side = 0; side < 2; ++side) {
    const Branch& mine = c.pieces[static_cast<std::size_t>(side)];
    const Branch& other = c.pieces[static_cast<std::size_t>(1 - side)];
    const Vec3 n = field.piece(p, mine).gradient.normalized();
    Vec3 t = along - n * n.dot(along);
    Vec3 left = n.cross(t);
    if (!(left.squaredNorm() > 0) || !left.allFinite())
      throw CreaseLayoutError("adaptive: a crease without a direction near " + format_point(p));
    left.normalize();
    Vec3 q = p + kSideProbe * min_edge * left;
    for (int it = 0; it < 3; ++it) {  // onto the piece's zero set: Newton along its gradient
      const FieldPiece f = field.piece(q, mine);
      q -= f.value / f.gradient.squaredNorm() * f.gradient;
    }
    const double F = field.value(q);
    const FieldPiece at_q = field.piece(q, mine), at_other = field.piece(q, other);
    const double mine_value = at_q.value, other_value = at_other.value;
    // Where the field takes the piece, unless it takes it only where two solids touch, on
    // either side of it the same sign (a box standing flush on a longer one: beside the step's
    // crease, the longer box's top face under the other box's bottom face, both zero there).
    const Vec3 m = at_q.gradient.normalized();
    const double depth = kSideDepth * kSideProbe * min_edge;
    bool closer = std::abs(F - mine_value) < std::abs(F - other_value);
    // On a seam hidden all along (traced from a corner where another ended), the pieces are one
    // function on either side: the side is the one where the field makes the seam's choice as
    // this piece does.
    Field::BranchRecord record;
    const std::size_t k = static_cast<std::size_t>(c.seam_branch);
    if (c.seam_branch >= 0 && same_to_rounding(mine_value, at_q.gradient, other_value, at_other.gradient) &&
        field.branch_record(q, record) && k < record.taken.size() && k < mine.size())
      closer = record.taken[k] == mine[k];
    const bool on_left = closer && surface_passes(field, q, m, depth);
    Dart& d = out[static_cast<std::size_t>(side)];
    d.curve = index;
    d.side = side;
    d.vertices = c.vertices;
    d.from = c.start_corner;
    d.to = c.end_corner;
    if (!on_left) {
      std::reverse(d.vertices.begin(), d.vertices.end());
      std::swap(d.from, d.to);
    }
  }
  // The two sides' patches lie on opposite sides of the crease, so their boundaries run opposite ways.
  if (out[0].vertices.front() == out[1].vertices.front() && out[0].vertices.size() > 2 &&
      out[0].vertices[1] == out[1].vertices[1])
    throw CreaseLayoutError("adaptive: both sides of the crease near " + format_point(p) +
                            " take the same piece's patch to the same side");
  return out;
}

bool same_function(const Field& field, const Branch& a, const Branch& b);

struct Cycle {
  Branch piece;
  std::vector<int> vertices;  // closed polygon, patch on the left
  double sagitta = 0;         // the largest of its curves' (LaidCurve::sagitta)
};

void fit_hidden_choices(const Field& field, const std::vector<bool>& movable, Cycle& cycle, std::span<const Vec3> points);

// The cycles that one tracker meshes, on one piece.
struct PatchGroup {
  std::vector<std::size_t> cycles;
  Branch piece;
};

// How far from a corner trace_cycles looks at the pieces meeting there, as a share of each dart's
// first edge: far beyond the corner's Newton tolerance (1e-10 of the diagonal), near enough that
// a curved piece's normal is the corner's.
constexpr double kCornerNudge = 1e-4;

// The boundary cycles of the pieces' patches: a loop's dart is a cycle by itself; a dart that
// ends at a corner goes on with the dart of the same piece that leaves the corner (the pieces
// compared by their gradients at the corner, since one piece may carry several branch codes).
// Where one plane's patches touch at a corner from opposite quadrants (the corners of a Menger
// sponge's central cavity, where each wall of a hole and the wall of a crossing hole are the
// same plane), two darts of that plane leave it: the patch's own is the first met turning
// clockwise (about the piece's normal) from the way the dart came, since the patch lies on
// the left of both, inside the angle between them.
std::vector<Cycle> trace_cycles(const Field& field, const std::vector<LaidCurve>& curves,
                                const std::vector<Dart>& darts, std::span<const Vec3> corners,
                                std::span<const Vec3> points) {
  std::vector<Cycle> cycles;
  std::vector<char> used(darts.size(), 0);
  const auto piece_of = [&](const Dart& d) -> const Branch& {
    return curves[static_cast<std::size_t>(d.curve)].pieces[static_cast<std::size_t>(d.side)];
  };
  for (std::size_t start = 0; start < darts.size(); ++start) {
    if (used[start]) continue;
    Cycle cycle;
    cycle.piece = piece_of(darts[start]);
    // The choices some dart leaves free or fixes otherwise than another: hidden somewhere on the
    // boundary. A choice every dart fixes alike is the patch's own.
    std::vector<bool> movable(cycle.piece.size(), false);
    std::size_t d = start;
    for (std::size_t guard = 0;; ++guard) {
      if (guard > darts.size()) throw CreaseLayoutError("adaptive: a patch boundary that does not close");
      used[d] = 1;
      const Dart& dart = darts[d];
      // A dart's code leaves free the choices hidden where it was taken (Field::pieces). Left
      // free over the whole patch, such a choice is the field's own wherever the tracker
      // evaluates, and bends the piece along the field's crease where a blend stops hiding it.
      // Two boxes smoothly united: the patch of one box's face behind the blend runs on to the
      // other box's face, whose edge then creased the piece itself; a front vertex landed on that
      // edge, made a zero-area triangle, and the creases were dropped. So a choice the cycle's
      // code leaves free is fixed as the first of its darts that fixes it does. (Choices two
      // darts fix differently keep the first's: freed, the flush faces of stairs, each fixing
      // its own box's hidden choices, made a piece of the whole field.) Where the piece so coded
      // is not the field just inside the patch, fit_hidden_choices refits them.
      for (std::size_t k = 0; k < movable.size() && k < piece_of(dart).size(); ++k)
        movable[k] = movable[k] || piece_of(dart)[k] == Field::kFreeBranch || piece_of(dart)[k] != piece_of(darts[start])[k];
      for (std::size_t k = 0; k < cycle.piece.size() && k < piece_of(dart).size(); ++k)
        if (cycle.piece[k] == Field::kFreeBranch) cycle.piece[k] = piece_of(dart)[k];
      if (dart.to < 0) {  // a loop
        cycle.vertices = dart.vertices;
        cycle.sagitta = curves[static_cast<std::size_t>(dart.curve)].sagitta;
        break;
      }
      cycle.vertices.insert(cycle.vertices.end(), dart.vertices.begin(), dart.vertices.end() - 1);
      cycle.sagitta = std::max(cycle.sagitta, curves[static_cast<std::size_t>(dart.curve)].sagitta);
      const Vec3& corner = corners[static_cast<std::size_t>(dart.to)];
      // Each piece looked at a hair from the corner along its own dart: at the corner itself a
      // choice its code leaves free may be either way (a seam over a box's top face, coded by
      // the cutter's walls with the box's choices free, ends on the box's edge, where the box
      // takes its top or its side by rounding: the top's patch was taken for the side's).
      const auto beside = [&](int v) {
        return corner + kCornerNudge * (points[static_cast<std::size_t>(v)] - corner);
      };
      const Vec3 g = field.piece(beside(dart.vertices[dart.vertices.size() - 2]), piece_of(dart)).gradient.normalized();
      std::size_t next = darts.size();
      std::vector<std::size_t> candidates;
      for (std::size_t e = 0; e < darts.size(); ++e) {
        if (darts[e].from != dart.to || darts[e].curve == dart.curve) continue;
        if (field.piece(beside(darts[e].vertices[1]), piece_of(darts[e])).gradient.normalized().dot(g) <= kSamePieceCosine)
          continue;
        candidates.push_back(e);
      }
      // Pieces tangent at the corner (where two creases of theirs cross) have the same
      // gradient there: the piece's own darts, where it has some, are the ones to follow. A
      // seam's darts stay candidates: where a seam runs into a crease (a box's switch hidden
      // under a smooth difference, running into the other box's edge), the face it splits is
      // another piece's on either side of it, and which dart bounds the patch is the turn's.
      if (candidates.size() > 1) {
        std::vector<std::size_t> own;
        for (const std::size_t e : candidates)
          if (same_function(field, piece_of(darts[e]), piece_of(dart)) ||
              curves[static_cast<std::size_t>(darts[e].curve)].seam_branch >= 0)
            own.push_back(e);
        if (!own.empty()) candidates = std::move(own);
      }
      if (candidates.size() == 1) next = candidates.front();
      if (candidates.size() > 1) {
        const auto at = [&](int v) { return points[static_cast<std::size_t>(v)]; };
        const Vec3 back = at(dart.vertices[dart.vertices.size() - 2]) - at(dart.vertices.back());
        double best = std::numeric_limits<double>::infinity();
        for (const std::size_t e : candidates) {
          const Vec3 out = at(darts[e].vertices[1]) - at(darts[e].vertices.front());
          double turn = std::atan2(g.dot(out.cross(back)), out.dot(back));  // counter-clockwise from out to back
          if (turn <= 0) turn += 2 * std::numbers::pi;
          if (turn < best) best = turn, next = e;
          else if (turn == best)
            throw CreaseLayoutError("adaptive: a piece meets the corner " + format_point(corner) +
                                    " more than once, along the same direction; its patch boundary is ambiguous");
        }
      }
      if (next == darts.size())
        throw CreaseLayoutError("adaptive: a patch boundary breaks off at the corner " + format_point(corner));
      if (next == start) break;
      if (used[next]) throw CreaseLayoutError("adaptive: patch boundaries cross at the corner " + format_point(corner));
      d = next;
    }
    if (cycle.vertices.size() < 3) throw CreaseLayoutError("adaptive: a patch bounded by fewer than three crease vertices");
    if (std::find(movable.begin(), movable.end(), true) != movable.end()) fit_hidden_choices(field, movable, cycle, points);
    cycles.push_back(std::move(cycle));
  }
  return cycles;
}

// Points spread over the box (the Halton sequence in bases 2, 3 and 5) where same_function
// compares two pieces. Three points on the box's diagonal all lay in the hole of a box minus a
// cylinder cut by a smooth difference, where the blend hides the box: its x and y faces were
// taken for one piece, meshed by one tracker, and their patches did not mesh.
constexpr int kSameFunctionPoints = 16;

double halton(int i, int base) {
  double f = 1, r = 0;
  for (; i > 0; i /= base) {
    f /= base;
    r += f * (i % base);
  }
  return r;
}

// Whether pieces a and b agree at p: equal values and gradients, to rounding.
bool same_at(const Field& field, const Branch& a, const Branch& b, const Vec3& p) {
  const auto [va, ga] = field.piece_first_order(p, a);
  const auto [vb, gb] = field.piece_first_order(p, b);
  return same_to_rounding(va, ga, vb, gb);
}

// Whether branch codes a and b give the same function: equal values and gradients at
// kSameFunctionPoints fixed points of the box (codes that differ only at branch points the
// piece does not pass through name one piece).
bool same_function(const Field& field, const Branch& a, const Branch& b) {
  if (a == b) return true;
  const Box& box = field.bounds();
  for (int i = 1; i <= kSameFunctionPoints; ++i)
    if (!same_at(field, a, b, box.min + Vec3(halton(i, 2), halton(i, 3), halton(i, 5)).cwiseProduct(box.size())))
      return false;
  return true;
}

// A share of each boundary edge's length: how far inside_points lie from it.
constexpr double kInsideStep = 0.25;

// Points just inside a patch bounded by the polygon `vertices`: each boundary edge's midpoint
// moved `share` of the edge to its left (the patch's side) in the tangent plane of `piece`; a
// negative share, just outside.
std::vector<Vec3> inside_points(const Field& field, const Branch& piece, std::span<const int> vertices,
                                std::span<const Vec3> points, double share) {
  std::vector<Vec3> out;
  const std::size_t n = vertices.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3& a = points[static_cast<std::size_t>(vertices[k])];
    const Vec3& b = points[static_cast<std::size_t>(vertices[(k + 1) % n])];
    const Vec3 m = 0.5 * (a + b);
    const Vec3 g = field.piece_first_order(m, piece).second;
    if (!(g.squaredNorm() > 0)) continue;
    out.push_back(m + share * g.normalized().cross(b - a));
  }
  return out;
}

bool same_near(const Field& field, const Branch& a, const Branch& b, std::span<const Vec3> at) {
  return std::all_of(at.begin(), at.end(), [&](const Vec3& p) { return same_at(field, a, b, p); });
}

// A cycle's code fixes the choices its darts fix where they were traced, some of them hidden there
// (trace_cycles). Where the piece so coded is not the field just inside the patch, the choices
// it fixes otherwise than the field takes them there are taken as the field takes them (or left
// free where it takes them both ways), if that makes it the field at every point inside. The
// bottom face of a box smoothly cut by another, whose choice of face is hidden all over it, took
// the other box's x face from the edge its first dart ran along: that piece is the face cut off
// by the other box's x plane, and the front stalled where the plane left the face.
void fit_hidden_choices(const Field& field, const std::vector<bool>& movable, Cycle& cycle, std::span<const Vec3> points) {
  // Inside as the piece with those choices free sees it: the piece as coded may be a plane
  // across the patch, whose tangent plane put the points on the boundary.
  Branch freed = cycle.piece;
  for (std::size_t k = 0; k < freed.size() && k < movable.size(); ++k)
    if (movable[k]) freed[k] = Field::kFreeBranch;
  const std::vector<Vec3> inside = inside_points(field, freed, cycle.vertices, points, kInsideStep);
  // The field there (every choice its own), evaluated once for the codes compared with it.
  const Branch own(cycle.piece.size(), Field::kFreeBranch);
  std::vector<std::pair<double, Vec3>> at_field;
  for (const Vec3& p : inside) at_field.push_back(field.piece_first_order(p, own));
  const auto is_field_at = [&](const Branch& code, std::size_t i) {
    const auto [value, gradient] = field.piece_first_order(inside[i], code);
    return same_to_rounding(at_field[i].first, at_field[i].second, value, gradient);
  };
  const auto is_field = [&](const Branch& code) {
    for (std::size_t i = 0; i < inside.size(); ++i)
      if (!is_field_at(code, i)) return false;
    return true;
  };
  constexpr std::uint8_t kUnset = 0xff;  // no point inside has taken the choice otherwise yet
  static_assert(kUnset != Field::kFreeBranch);
  Branch taken(cycle.piece.size(), kUnset);
  bool any = false;
  for (std::size_t i = 0; i < inside.size(); ++i) {
    if (is_field_at(cycle.piece, i)) continue;
    Field::BranchRecord record;
    if (!field.branch_record(inside[i], record)) return;
    for (std::size_t k = 0; k < cycle.piece.size() && k < record.taken.size() && k < movable.size(); ++k) {
      if (!movable[k] || cycle.piece[k] == Field::kFreeBranch || record.taken[k] == cycle.piece[k]) continue;
      taken[k] = taken[k] == kUnset || taken[k] == record.taken[k] ? record.taken[k] : Field::kFreeBranch;
      any = true;
    }
  }
  if (!any) return;
  Branch fitted = cycle.piece;
  for (std::size_t k = 0; k < taken.size(); ++k)
    if (taken[k] != kUnset) fitted[k] = taken[k];
  if (is_field(fitted)) cycle.piece = std::move(fitted);
  else if (is_field(freed)) cycle.piece = std::move(freed);
}

// One code for two pieces that are one function near their boundaries: a choice either fixes is
// fixed, a choice they fix differently is left free (a smooth difference hides the box along a
// tunnel's wall, whose two mouths' faces fix the box's abs differently).
Branch merge_codes(const Branch& a, const Branch& b) {
  Branch out = a;
  for (std::size_t k = 0; k < out.size() && k < b.size(); ++k) {
    if (out[k] == Field::kFreeBranch) out[k] = b[k];
    else if (b[k] != Field::kFreeBranch && b[k] != out[k]) out[k] = Field::kFreeBranch;
  }
  return out;
}

// Whether no branch point is fixed one way in a and the other in b.
bool compatible(const Branch& a, const Branch& b) {
  for (std::size_t k = 0; k < a.size() && k < b.size(); ++k)
    if (a[k] != Field::kFreeBranch && b[k] != Field::kFreeBranch && a[k] != b[k]) return false;
  return true;
}

// The region growth's step, as a share of the median crease edge: a smaller step than the
// patches' boundaries have, so that a step does not jump a patch as narrow as a crease edge.
// Between the box's diagonal over kRegionStepsMax and over kRegionStepsMin: a patch's width does
// not shrink with the tolerance (at 1e-4 the crease edges' half made 200,000 samples and more).
constexpr double kRegionStep = 0.5;
constexpr double kRegionStepsMin = 40, kRegionStepsMax = 100;
// Bounds of the region growth below: samples in all, and Newton steps onto the surface for one.
constexpr std::size_t kMaxRegionSamples = 200000;
constexpr int kRegionNewtonSteps = 8;

// Which cycles bound one smooth region of the surface: regions grown from just inside every
// cycle, in steps of `step` over the surface (six ways in the tangent plane, each point moved
// onto F by Newton), a step kept where the field's own code there (Field::pieces, its hidden
// choices free) fixes no branch point otherwise than the code it came from: a step across a
// crease changes a visible choice. Where the growth of two cycles meets (samples within half a
// step, compatible codes), the cycles bound one region. Empty if the growth would exceed
// kMaxRegionSamples: the cycles are then grouped by function only.
std::vector<int> cycle_regions(const Field& field, const std::vector<Cycle>& cycles,
                               const std::vector<std::vector<Vec3>>& inside, double step) {
  UnionFind regions(cycles.size());
  struct Sample {
    Vec3 p, normal;
    Branch code;
    int cycle;
  };
  std::vector<Sample> samples;
  SpatialHash hash(step);
  const auto onto_surface = [&](Vec3 q) -> std::optional<std::pair<Vec3, Vec3>> {
    for (int it = 0; it < kRegionNewtonSteps; ++it) {
      Vec3 g;
      const double v = field.value_gradient(q, g);
      if (!std::isfinite(v) || !(g.squaredNorm() > 0)) return std::nullopt;
      const double d = v / g.norm();
      q -= d * g.normalized();
      if (std::abs(d) <= 1e-3 * step) return std::pair{q, g};
    }
    return std::nullopt;
  };
  // Adds a sample unless one within half a step has a compatible code (then their cycles meet).
  const auto add = [&](const Vec3& p, const Vec3& gradient, Branch code, int cycle) {
    bool near = false;
    hash.for_each_near(p, 0.5 * step, [&](int id) {
      const Sample& s = samples[static_cast<std::size_t>(id)];
      if ((s.p - p).norm() <= 0.5 * step && compatible(s.code, code)) {
        regions.unite(s.cycle, cycle);
        near = true;
      }
    });
    if (near) return;
    hash.insert(static_cast<int>(samples.size()), p);
    samples.push_back({p, gradient.normalized(), std::move(code), cycle});
  };
  RegionCodes codes(field, step);
  for (std::size_t i = 0; i < cycles.size(); ++i)
    for (const Vec3& x : inside[i])
      if (const auto q = onto_surface(x)) {
        Branch code = codes.at(q->first);
        if (compatible(code, cycles[i].piece)) add(q->first, q->second, std::move(code), static_cast<int>(i));
      }
  // Whether the region of `cycle` has a sample within half a step of c: then nothing there is
  // evaluated (most of a sample's six steps land beside samples already grown).
  const auto covered = [&](const Vec3& c, int cycle) {
    bool found = false;
    const int root = regions.find(cycle);
    hash.for_each_near(c, 0.5 * step, [&](int id) {
      const Sample& o = samples[static_cast<std::size_t>(id)];
      found = found || ((o.p - c).norm() <= 0.5 * step && regions.find(o.cycle) == root);
    });
    return found;
  };
  // Breadth first: the samples in the order they were added. A copy, since adding reallocates.
  for (std::size_t head = 0; head < samples.size(); ++head) {
    if (samples.size() > kMaxRegionSamples) return {};
    const Sample s = samples[head];
    const Vec3 t1 = s.normal.unitOrthogonal(), t2 = s.normal.cross(t1);
    for (int k = 0; k < 6; ++k) {
      const double angle = k * std::numbers::pi / 3;
      const Vec3 c = s.p + step * (std::cos(angle) * t1 + std::sin(angle) * t2);
      if (covered(c, s.cycle)) continue;
      const auto q = onto_surface(c);
      if (!q || (q->first - s.p).norm() > 2 * step || !field.bounds().contains(q->first)) continue;
      Branch code = codes.at(q->first);
      if (compatible(code, s.code)) add(q->first, q->second, std::move(code), s.cycle);
    }
  }
  std::vector<int> out(cycles.size());
  for (std::size_t i = 0; i < cycles.size(); ++i) out[i] = regions.find(static_cast<int>(i));
  return out;
}

// The cycles grouped by function: one group per piece (same_function), on the first's code.
std::vector<PatchGroup> group_by_function(const Field& field, const std::vector<Cycle>& cycles,
                                          std::span<const std::size_t> which) {
  std::vector<PatchGroup> groups;
  for (const std::size_t i : which) {
    const auto g = std::find_if(groups.begin(), groups.end(), [&](const PatchGroup& g) {
      return same_function(field, cycles[g.cycles.front()].piece, cycles[i].piece);
    });
    if (g != groups.end()) g->cycles.push_back(i);
    else groups.push_back({{i}, cycles[i].piece});
  }
  return groups;
}

// The cycles of one smooth region belong together: the boundaries of one patch (a face with a
// hole) must meet and merge. Without hidden choices a region is one function, and its cycles are
// grouped by function. With them (behind a smooth blend, Field::pieces leaves a hidden choice
// free), one region may be coded differently along its boundaries: behind a smooth difference, a
// face, its fillet and a tunnel's wall are one patch, its outer boundary (the face's edges)
// coded by the box's choice with the tunnels' hidden, its inner one (where two tunnels cross)
// by the tunnels' choice with the box's hidden. Grouped by function, two trackers meshed that
// wall from both sides, and their fronts stalled where they met. So the cycles are grouped by
// region (cycle_regions), each region on one code (merge_codes) where that code is the same
// function as each cycle's piece on both sides of its boundary (where the tracker evaluates
// it), and otherwise by function within the region; groups of one function are then joined.
std::vector<PatchGroup> group_cycles(const Field& field, const std::vector<Cycle>& cycles, std::span<const Vec3> points) {
  std::vector<std::size_t> all(cycles.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  std::vector<PatchGroup> by_function = group_by_function(field, cycles, all);
  const auto has_free = [](const PatchGroup& g) {
    return std::count(g.piece.begin(), g.piece.end(), Field::kFreeBranch) > 0;
  };
  if (by_function.size() < 2 || std::none_of(by_function.begin(), by_function.end(), has_free)) return by_function;
  std::vector<std::vector<Vec3>> inside, outside;
  std::vector<double> edges;
  for (const Cycle& c : cycles) {
    inside.push_back(inside_points(field, c.piece, c.vertices, points, kInsideStep));
    outside.push_back(inside_points(field, c.piece, c.vertices, points, -kInsideStep));
    for (std::size_t k = 0; k < c.vertices.size(); ++k)
      edges.push_back((points[static_cast<std::size_t>(c.vertices[k])] -
                       points[static_cast<std::size_t>(c.vertices[(k + 1) % c.vertices.size()])]).norm());
  }
  // Only where two cycles of different functions could share a piece can a region hold both.
  const auto valid_for = [&](const Branch& code, std::size_t k) {
    return same_near(field, code, cycles[k].piece, inside[k]) && same_near(field, code, cycles[k].piece, outside[k]);
  };
  bool any_pair = false;
  for (std::size_t a = 0; a < by_function.size() && !any_pair; ++a)
    for (std::size_t b = a + 1; b < by_function.size() && !any_pair; ++b)
      for (const std::size_t i : by_function[a].cycles)
        for (const std::size_t j : by_function[b].cycles) {
          const Branch code = merge_codes(cycles[i].piece, cycles[j].piece);
          if (valid_for(code, i) && valid_for(code, j)) any_pair = true;
        }
  if (!any_pair) return by_function;
  std::nth_element(edges.begin(), edges.begin() + static_cast<std::ptrdiff_t>(edges.size() / 2), edges.end());
  const double diagonal = field.bounds().size().norm();
  const double step = std::clamp(kRegionStep * edges[edges.size() / 2], diagonal / kRegionStepsMax, diagonal / kRegionStepsMin);
  const std::vector<int> region = cycle_regions(field, cycles, inside, step);
  if (region.empty()) return by_function;
  std::vector<PatchGroup> groups;
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    if (region[i] != static_cast<int>(i)) continue;  // each region once, at its first cycle
    PatchGroup g;
    for (std::size_t j = i; j < cycles.size(); ++j)
      if (region[j] == static_cast<int>(i)) g.cycles.push_back(j);
    g.piece = cycles[i].piece;
    for (const std::size_t j : g.cycles) g.piece = merge_codes(g.piece, cycles[j].piece);
    const bool valid = std::all_of(g.cycles.begin(), g.cycles.end(), [&](std::size_t k) { return valid_for(g.piece, k); });
    if (valid) groups.push_back(std::move(g));
    else
      for (PatchGroup& h : group_by_function(field, cycles, g.cycles)) groups.push_back(std::move(h));
  }
  // Regions of one function in one tracker, as without hidden choices.
  std::vector<PatchGroup> out;
  for (PatchGroup& g : groups) {
    const auto h = std::find_if(out.begin(), out.end(), [&](const PatchGroup& h) { return same_function(field, h.piece, g.piece); });
    if (h == out.end()) {
      out.push_back(std::move(g));
      continue;
    }
    h->cycles.insert(h->cycles.end(), g.cycles.begin(), g.cycles.end());
    std::sort(h->cycles.begin(), h->cycles.end());
  }
  return out;
}

// The patch tests' margin, as a share of an edge's length or a placement's step (see below).
constexpr double kOutsidePatch = 0.1;

// Whether the straight edge a-b (two crease vertices of the piece `branch`) runs over the
// piece's patches: its midpoint, moved onto the piece, is where the CSG field takes the piece.
// Elsewhere the field takes another piece, whose value there is about the distance to its zero
// set; a share kOutsidePatch of the edge's length tells that from the tolerance of points on
// the crease (a chord of a curved crease leaves the patch by its sagitta only).
bool inside_patch(const Field& field, const Branch& branch, const Vec3& a, const Vec3& b) {
  Vec3 m = 0.5 * (a + b);
  for (int it = 0; it < 3; ++it) {
    const auto [value, gradient] = field.piece_first_order(m, branch);
    if (!(gradient.squaredNorm() > 0)) return false;
    m -= value / gradient.squaredNorm() * gradient;
  }
  const auto [value, gradient] = field.piece_first_order(m, branch);
  return std::abs(field.value(m) - value) <= kOutsidePatch * (a - b).norm() * gradient.norm();
}

// Whether x, a point of the piece `branch` placed with step d, lies in the piece's patches: the
// CSG field takes the piece there, up to the same share of d and twice the boundary's sagitta.
// The boundary polygon's chords stray from the crease by up to `sagitta`, into the neighbouring
// patch where the crease bends away from this one, and points next to them may too.
bool in_patch(const Field& field, const Branch& branch, const Vec3& x, double d, double sagitta) {
  const auto [value, gradient] = field.piece_first_order(x, branch);
  return std::abs(field.value(x) - value) <= (kOutsidePatch * d + 2 * sagitta) * gradient.norm();
}

// Patch vertices off the field's surface by more than this share of the diagonal (10^4 times
// the Newton tolerance the trackers place them to) lie where the field is not their piece.
constexpr double kOffPiece = 1e-6;
// ... and are moved onto the field's surface by Newton (at its tolerance) if that moves them by at
// most this share of the edge length they were placed with; else the layout fails.
constexpr double kOffPieceTravel = 0.25;

// The vertices from `first` on that a patch's tracker placed on its piece where the field is
// another function: moved onto the field's surface (land_on_field, crease_patches.h).
void land_on_field(const Field& field, CreaseMesh& out, std::size_t first, double diagonal) {
  std::vector<Vec3>& points = out.mesh.positions;
  if (points.size() <= first) return;
  const std::size_t n = points.size() - first;
  std::vector<double> values(n);
  std::vector<Vec3> gradients(n);
  field.values_gradients(points.data() + first, values.data(), gradients.data(), n);
  for (std::size_t i = 0; i < n; ++i) {
    const double g = gradients[i].norm();
    if (!(g > 0) || !(std::abs(values[i]) > kOffPiece * diagonal * g)) continue;
    const std::size_t v = first + i;
    ProjectionOptions po;
    po.tolerance = 1e-10 * diagonal;
    const double reach = kOffPieceTravel * out.target[v];
    po.max_step = po.max_travel = std::isfinite(reach) && reach > 0 ? reach : kOffPiece * diagonal;
    const ProjectionResult r = project_to_surface(field, points[v], po);
    if (!r.ok() || !(r.gradient.squaredNorm() > 0))
      throw CreaseLayoutError("adaptive: a patch vertex near " + format_point(points[v]) + " lies " +
                              std::to_string(std::abs(values[i]) / g) +
                              " off the surface, where the field is not its patch's piece");
    points[v] = r.point;
    out.mesh.normals[v] = r.gradient.normalized();
    ++out.landed;
  }
}

// One group's patches meshed by a tracker of its own (mesh_crease_patches runs them on several
// threads: nothing here is shared but the field and what is read).
struct PatchPart {
  Mesh mesh;
  std::vector<std::vector<int>> ids;  // the tracker's vertex of each group cycle's vertex
  std::vector<double> target, mac, shape_index;
  std::size_t steps = 0, splits = 0, merges = 0, forced_closures = 0, patch_refusals = 0;
  std::pair<double, Vec3> tightest{std::numeric_limits<double>::infinity(), Vec3::Zero()};
  std::exception_ptr error;
};

PatchPart mesh_patch_group(const Field& field, const PatchGroup& patch, const std::vector<Cycle>& cycles,
                           const std::vector<Vec3>& points, const Settings& settings, const CancelToken& cancel,
                           double estimated_area, double look_ahead_gradation) {
  PatchPart out;
  const Branch& branch = patch.piece;
  const PieceField piece(field, branch);
  std::vector<std::vector<Tracker::Placed>> loops;
  for (const std::size_t i : patch.cycles) {
    std::vector<Tracker::Placed>& loop = loops.emplace_back();
    for (const int v : cycles[i].vertices) {
      const Vec3& p = points[static_cast<std::size_t>(v)];
      const FieldPiece q = field.piece(p, branch);
      loop.push_back({p, curvature_from_derivatives(q.gradient, q.hessian)});
    }
  }
  Settings patch_settings = settings;
  patch_settings.look_ahead = true;
  patch_settings.look_ahead_gradation = look_ahead_gradation;
  patch_settings.cancel = cancel;
  Tracker tracker(piece, patch_settings, out.mesh);
  if (estimated_area > 0) tracker.set_estimated_area(estimated_area);
  tracker.set_patch_test([&field, &branch](const Vec3& a, const Vec3& b) { return inside_patch(field, branch, a, b); });
  double sagitta = 0;
  for (const std::size_t i : patch.cycles) sagitta = std::max(sagitta, cycles[i].sagitta);
  tracker.set_point_test(
      [&field, &branch, sagitta](const Vec3& x, double d) { return in_patch(field, branch, x, d, sagitta); });
  out.ids = tracker.mesh_from_loops(loops);
  out.target = tracker.vertex_edge_length();
  out.mac = tracker.vertex_mac();
  out.shape_index = tracker.vertex_shape_index();
  out.steps = tracker.steps();
  out.splits = tracker.splits();
  out.merges = tracker.merges();
  out.forced_closures = tracker.forced_closures();
  out.patch_refusals = tracker.patch_refusals();
  out.tightest = tracker.tightest_bend();
  return out;
}

}  // namespace

CreaseMesh start_shared(const std::vector<Vec3>& shared) {
  CreaseMesh out;
  const std::size_t n = shared.size();
  out.mesh.positions = shared;
  out.mesh.normals.assign(n, Vec3::Zero());
  out.target.assign(n, std::numeric_limits<double>::infinity());
  out.mac.assign(n, 0.0);
  out.shape_index.assign(n, 0.0);
  return out;
}

void add_part(CreaseMesh& out, const Mesh& part, const std::vector<std::vector<int>>& loop_ids,
              const std::vector<std::vector<int>>& shared_ids, std::span<const double> target,
              std::span<const double> mac, std::span<const double> shape_index) {
  Mesh& mesh = out.mesh;
  std::vector<int> to_global(part.positions.size(), -1);
  for (std::size_t l = 0; l < loop_ids.size(); ++l)
    for (std::size_t k = 0; k < loop_ids[l].size(); ++k)
      to_global[static_cast<std::size_t>(loop_ids[l][k])] = shared_ids[l][k];
  for (std::size_t v = 0; v < part.positions.size(); ++v) {
    int& g = to_global[v];
    if (g < 0) {
      g = static_cast<int>(mesh.positions.size());
      mesh.positions.push_back(part.positions[v]);
      mesh.normals.push_back(part.normals[v]);
      out.target.push_back(target[v]);
      out.mac.push_back(mac[v]);
      out.shape_index.push_back(shape_index[v]);
    } else {
      const auto gv = static_cast<std::size_t>(g);
      mesh.normals[gv] += part.normals[v];
      out.target[gv] = std::min(out.target[gv], target[v]);
      if (mac[v] >= out.mac[gv]) out.mac[gv] = mac[v], out.shape_index[gv] = shape_index[v];
    }
  }
  for (const auto& t : part.triangles)
    mesh.triangles.push_back({to_global[static_cast<std::size_t>(t[0])], to_global[static_cast<std::size_t>(t[1])],
                              to_global[static_cast<std::size_t>(t[2])]});
}

void finish_shared(CreaseMesh& out, std::size_t shared, const std::string& unreached) {
  Mesh& mesh = out.mesh;
  for (std::size_t v = 0; v < shared; ++v) {
    if (!(mesh.normals[v].squaredNorm() > 0))
      throw CreaseLayoutError("adaptive: " + unreached + " near " + format_point(mesh.positions[v]));
    mesh.normals[v].normalize();
  }
}

CreaseMesh mesh_crease_patches(const Field& field, const CreaseTracingResult& creases, const Settings& settings,
                               double estimated_area, double look_ahead_gradation, int threads) {
  CreaseMesh out;
  const double diagonal = settings.diagonal;
  CreaseVertices cv;
  std::vector<int> corner_vertex;
  for (const Vec3& c : creases.corners) corner_vertex.push_back(cv.add(c));

  // The corners at the curves' ends, for the feature size (resample_curve checks them).
  std::vector<int> start_corner(creases.curves.size(), -1), end_corner(creases.curves.size(), -1);
  for (std::size_t c = 0; c < creases.curves.size(); ++c) {
    const CreaseCurve& curve = creases.curves[c];
    if (curve.closed || curve.points.empty()) continue;
    for (std::size_t k = 0; k < creases.corners.size(); ++k) {
      if ((creases.corners[k] - curve.points.front()).norm() <= kCornerMatch * diagonal) start_corner[c] = static_cast<int>(k);
      if ((creases.corners[k] - curve.points.back()).norm() <= kCornerMatch * diagonal) end_corner[c] = static_cast<int>(k);
    }
  }
  const auto feature = crease_feature_size(creases, start_corner, end_corner, settings.sizing.max_edge);
  std::vector<LaidCurve> curves;
  for (std::size_t c = 0; c < creases.curves.size(); ++c)
    curves.push_back(resample_curve(field, creases.curves[c], feature[c], settings.sizing, corner_vertex, creases.corners,
                                    diagonal, cv));
  std::vector<Dart> darts;
  for (std::size_t i = 0; i < curves.size(); ++i)
    for (Dart& d : orient_darts(field, curves[i], static_cast<int>(i), cv, creases.curves[i].points, settings.sizing.min_edge))
      darts.push_back(std::move(d));
  const std::vector<Cycle> cycles = trace_cycles(field, curves, darts, creases.corners, cv.points);

  const std::vector<PatchGroup> groups = group_cycles(field, cycles, cv.points);
  const std::size_t nc = cv.points.size();
  // Each group's tracker into its own slot, on `threads` threads for a thread-safe field, the
  // largest groups (by boundary vertices) first; the parts joined in group order, so the mesh is
  // the same on any number of threads. Where a group fails, the first failing one in group order
  // decides, as on one thread: a failure cancels the groups after it (their parts could change
  // nothing), and those before it run to their end.
  std::vector<PatchPart> parts(groups.size());
  std::vector<CancelToken> stops(groups.size());
  for (CancelToken& t : stops) t = settings.cancel.linked();
  const auto run_group = [&](std::size_t g) {
    try {
      parts[g] = mesh_patch_group(field, groups[g], cycles, cv.points, settings, stops[g], estimated_area,
                                  look_ahead_gradation);
    } catch (...) {
      parts[g].error = std::current_exception();
      for (std::size_t later = g + 1; later < groups.size(); ++later) stops[later].cancel();
    }
  };
  std::vector<std::size_t> order(groups.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto weight = [&](std::size_t g) {
    std::size_t w = 0;
    for (const std::size_t i : groups[g].cycles) w += cycles[i].vertices.size();
    return w;
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return weight(x) > weight(y); });
  const unsigned workers = field.thread_safe() ? detail::worker_count(threads) : 1u;
  detail::parallel_blocks(order.size(), 1, workers, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) run_group(order[i]);
  });
  for (const PatchPart& p : parts)
    if (p.error) std::rethrow_exception(p.error);
  out = start_shared(cv.points);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    PatchPart& p = parts[g];
    std::vector<std::vector<int>> shared;
    for (const std::size_t i : groups[g].cycles) shared.push_back(cycles[i].vertices);
    add_part(out, p.mesh, p.ids, shared, p.target, p.mac, p.shape_index);
    out.steps += p.steps;
    out.splits += p.splits;
    out.merges += p.merges;
    out.forced_closures += p.forced_closures;
    out.patch_refusals += p.patch_refusals;
    if (p.tightest.first < out.tightest.first) out.tightest = p.tightest;
    out.group_ends.push_back(out.mesh.triangles.size());
    p = PatchPart{};  // its memory back before the next is joined
  }
  finish_shared(out, nc, "a crease vertex no patch reached");
  out.crease_vertices = nc;
  out.pieces = groups.size();
  land_on_field(field, out, nc, diagonal);
  return out;
}

std::vector<std::uint8_t> RegionCodes::at(const Vec3& p) {
  Field::BranchRecord record;
  if (!field_.branch_record(p, record)) return {};
  const bool near_switch = std::any_of(record.distance.begin(), record.distance.end(),
                                       [&](double d) { return !(d > kFreshCode * step_); });
  if (!near_switch)
    if (const auto known = known_.find(record.taken); known != known_.end()) return known->second;
  ++fresh_;
  const std::vector<FieldPiece> pieces = field_.pieces_first_order(p, 0);
  std::vector<std::uint8_t> code = pieces.empty() ? std::vector<std::uint8_t>{} : pieces.front().branch;
  if (!near_switch) known_.emplace(std::move(record.taken), code);
  return code;
}

}  // namespace cdp::adaptive
