// The pieces of a creased field (Field::pieces, the expression model) and the projection onto
// its creases and corners (crease.h), against closed forms: a cube's faces, edges and corners,
// two unioned spheres' circle, a capped cylinder's rims.
#include <gtest/gtest.h>

#include <cdp/core/crease.h>
#include <cdp/core/curvature.h>
#include <cdp/core/crease_curves.h>
#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/models/autodiff_field.h>
#include <cdp/core/models/compiled.h>
#include <cdp/core/models/expression.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <span>
#include <set>
#include <string>
#include <type_traits>

#include "common/test_fields.h"

namespace cdp {
namespace {

Expression crease_expression(const std::string& formula, double half = 2) {
  return Expression(formula, {}, Box{Vec3::Constant(-half), Vec3::Constant(half)});
}

const char* kCubeFormula = "max(abs(x),max(abs(y),abs(z)))-1";

// The pieces' gradients at p, as a set (order-free comparison).
// Whether the tracing found a corner within 1e-6 of t.
bool has_corner(const CreaseTracingResult& r, const Vec3& t) {
  return std::any_of(r.corners.begin(), r.corners.end(), [&](const Vec3& c) { return (c - t).norm() < 1e-6; });
}

std::set<std::array<double, 3>> gradients(const std::vector<FieldPiece>& pieces) {
  std::set<std::array<double, 3>> out;
  for (const auto& q : pieces) out.insert({q.gradient.x(), q.gradient.y(), q.gradient.z()});
  return out;
}

TEST(FieldPieces, ACubeHasOnePieceOnAFaceTwoOnAnEdgeThreeAtACorner) {
  const Expression cube = crease_expression(kCubeFormula);
  // On a face, away from the edges: the face's plane x - 1.
  auto face = cube.pieces(Vec3(1, 0.5, 0.2), 0.1);
  ASSERT_EQ(face.size(), 1u);
  EXPECT_EQ(face[0].gradient, Vec3(1, 0, 0));
  EXPECT_DOUBLE_EQ(face[0].value, 0);
  // Near the edge x = y = 1 (within the radius): the two faces' planes, the face the point is
  // on first.
  auto edge = cube.pieces(Vec3(1, 0.95, 0.2), 0.1);
  ASSERT_EQ(edge.size(), 2u);
  EXPECT_EQ(edge[0].gradient, Vec3(1, 0, 0));
  EXPECT_EQ(edge[1].gradient, Vec3(0, 1, 0));
  EXPECT_NEAR(edge[1].value, 0.95 - 1, 1e-16);
  EXPECT_EQ(edge[1].hessian, Mat3::Zero());
  // The same point with a radius that does not reach the edge.
  EXPECT_EQ(cube.pieces(Vec3(1, 0.95, 0.2), 0.01).size(), 1u);
  // A corner: three planes.
  auto corner = cube.pieces(Vec3(0.98, -0.99, 1.0), 0.05);
  EXPECT_EQ(gradients(corner), (std::set<std::array<double, 3>>{{1, 0, 0}, {0, -1, 0}, {0, 0, 1}}));
}

TEST(FieldPieces, APieceKeepsItsBranchesAwayFromWhereItWasFound) {
  const Expression cube = crease_expression(kCubeFormula);
  const auto edge = cube.pieces(Vec3(1, 0.95, 0.2), 0.1);
  ASSERT_EQ(edge.size(), 2u);
  // The y-face's plane y - 1, evaluated far inside the x-face's part of the field.
  const FieldPiece far = cube.piece(Vec3(1.5, -0.3, 0.7), edge[1].branch);
  EXPECT_DOUBLE_EQ(far.value, -1.3);
  EXPECT_EQ(far.gradient, Vec3(0, 1, 0));
  EXPECT_THROW(cube.piece(Vec3::Zero(), {0, 1}), InvalidInputError);  // the cube has 5 branch points
}

TEST(FieldPieces, DerivativesOfAPieceMatchFiniteDifferences) {
  // Two unioned spheres: min of two distances; each piece is one sphere's distance.
  const Expression spheres = crease_expression("min(sqrt((x-0.5)^2+y^2+z^2)-1, sqrt((x+0.5)^2+y^2+z^2)-1)");
  const Vec3 p(0.01, 0.8, 0.3);
  const auto pieces = spheres.pieces(p, 0.05);
  ASSERT_EQ(pieces.size(), 2u);
  for (const auto& q : pieces) {
    const double h = 1e-6;
    for (int a = 0; a < 3; ++a) {
      const Vec3 e = Vec3::Unit(a) * h;
      const FieldPiece plus = spheres.piece(p + e, q.branch), minus = spheres.piece(p - e, q.branch);
      EXPECT_NEAR((plus.value - minus.value) / (2 * h), q.gradient[a], 1e-8);
      EXPECT_NEAR(((plus.gradient - minus.gradient) / (2 * h) - q.hessian.col(a)).norm(), 0, 1e-7);
    }
  }
  // The piece whose centre is (0.5, 0, 0): its value is the distance to that centre minus 1.
  const bool first_is_right = pieces[0].gradient.x() < 0;
  const FieldPiece& right = first_is_right ? pieces[0] : pieces[1];
  EXPECT_NEAR(right.value, (p - Vec3(0.5, 0, 0)).norm() - 1, 1e-15);
}

TEST(FieldPieces, OnlyModelsWithBranchPointsHavePieces) {
  EXPECT_TRUE(crease_expression(kCubeFormula).has_pieces());
  EXPECT_TRUE(crease_expression("abs(x)+y^2+z^2-1").has_pieces());  // a lens: its rim is a crease
  // Two planes: abs switches at x = 0, away from the surface, so no crease (Field::branch_kinds).
  EXPECT_FALSE(crease_expression("abs(x)-1").has_pieces());
  EXPECT_FALSE(crease_expression("x^2+y^2+z^2-1").has_pieces());
  EXPECT_FALSE(Sphere(Vec3::Zero(), 1.0).has_pieces());
}

TEST(FieldPieces, SmoothModelsReportNoPiecesAndCountTheirEvaluations) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  EXPECT_TRUE(sphere.pieces(Vec3(1, 0, 0), 0.1).empty());
  // The empty branch is the field itself.
  const FieldPiece whole = sphere.piece(Vec3(2, 0, 0), {});
  EXPECT_DOUBLE_EQ(whole.value, sphere.value(Vec3(2, 0, 0)));
  EXPECT_THROW(sphere.piece(Vec3::Zero(), {1}), InvalidInputError);
  const Expression cube = crease_expression(kCubeFormula);
  // The branch points' kinds are found once, with evaluations of their own (tested below).
  cube.branch_kinds();
  cube.reset_counts();
  const auto corner = cube.pieces(Vec3(1, 1, 1), 0.01);
  EXPECT_EQ(corner.size(), 3u);
  EXPECT_EQ(cube.counts().value_gradient, 1u);
  EXPECT_EQ(cube.counts().gradient_hessian, 3u);
}

// An expression that does not say which choices its values depend on, so that its pieces come
// from every combination of the choices near the point (Field::pieces' general way); and one
// that counts the evaluations made either way.
class EveryCombination : public Expression {
 public:
  using Expression::Expression;
  mutable std::size_t evaluations = 0;

 protected:
  bool eval_piece_live(const Vec3&, const std::vector<std::uint8_t>&, const std::int8_t*, bool, FieldPiece&,
                       std::uint64_t&) const override {
    return false;
  }
  std::pair<double, Vec3> eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const override {
    ++evaluations;
    return Expression::eval_first_order(p, branch);
  }
  // Each combination counts as one evaluation, as it was before Expression got them from one run.
  void eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base, std::span<const int> split,
                                     std::vector<std::pair<double, Vec3>>& out) const override {
    evaluations += std::size_t{1} << split.size();
    Expression::eval_first_order_combinations(p, base, split, out);
  }
};
class CountedLive : public Expression {
 public:
  using Expression::Expression;
  mutable std::size_t evaluations = 0;

 protected:
  bool eval_piece_live(const Vec3& p, const std::vector<std::uint8_t>& branch, const std::int8_t* bits, bool hessian,
                       FieldPiece& piece, std::uint64_t& live) const override {
    ++evaluations;
    return Expression::eval_piece_live(p, branch, bits, hessian, piece, live);
  }
};

void expect_same_pieces(const std::vector<FieldPiece>& a, const std::vector<FieldPiece>& b, const std::string& where) {
  ASSERT_EQ(a.size(), b.size()) << where;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].branch, b[i].branch) << where << " piece " << i;
    EXPECT_EQ(a[i].value, b[i].value) << where << " piece " << i;
    EXPECT_EQ(a[i].gradient, b[i].gradient) << where << " piece " << i;
    EXPECT_EQ(a[i].hessian, b[i].hessian) << where << " piece " << i;
  }
}

// Pieces found by trying a choice both ways only where the value depends on it are those of
// every combination, bit for bit and in the same order, with and without Hessians: at random
// points near CSG shapes whose choices hide each other (a Menger sponge's abs under its maxes, a
// tetrahedron's |x - y| under a max, a shared sub-expression, a clamp), at several radii. At the
// sponge's inner corner the search makes under a third of the evaluations.
TEST(FieldPieces, ChoicesTriedOnlyWhereTheValueDependsOnThemGiveThePiecesOfEveryCombination) {
  const Box box{Vec3::Constant(-1.3), Vec3::Constant(1.3)};
  const std::map<std::string, std::string> none;
  const std::vector<std::pair<std::string, std::map<std::string, std::string>>> models = {
      {"max(max(abs(x),abs(y),abs(z))-1, -min(max(abs(x),abs(y))-0.4, max(abs(y),abs(z))-0.4, max(abs(x),abs(z))-0.4))",
       none},
      {"max(abs(x+y)-z, abs(x-y)+z)-0.5", none},
      {"max(a, -min(hypot(y,z)-0.5, hypot(x,z)-0.5, hypot(x,y)-0.5))", {{"a", "max(hypot(x,y,z)-1, max(abs(x),abs(y),abs(z))-0.75)"}}},
      {"min(max(abs(x)-0.5, abs(y)-0.5, abs(z)-0.5), clamp(x, -0.2, 0.3) + abs(y) - 0.8)", none}};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coordinate(-1.1, 1.1);
  for (const auto& [formula, definitions] : models) {
    const EveryCombination every(formula, {}, box, definitions);
    const Expression live(formula, {}, box, definitions);
    ASSERT_TRUE(live.has_pieces()) << formula;
    for (int i = 0; i < 300; ++i) {
      const Vec3 p(coordinate(rng), coordinate(rng), coordinate(rng));
      for (const double radius : {0.05, 0.2, 0.6}) {
        const std::string where = formula + " at " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " +
                                  std::to_string(p.z()) + " radius " + std::to_string(radius);
        expect_same_pieces(live.pieces(p, radius), every.pieces(p, radius), where);
        expect_same_pieces(live.pieces_first_order(p, radius), every.pieces_first_order(p, radius), where);
      }
    }
  }
  // The sponge's inner corner (0.4, 0.4, 0.4), where three holes' walls and their choices meet.
  const std::string sponge = models[0].first;
  const EveryCombination every(sponge, {}, box);
  const CountedLive counted(sponge, {}, box);
  const Vec3 corner(0.41, 0.39, 0.4);
  every.branch_kinds();
  counted.branch_kinds();
  every.evaluations = 0;
  expect_same_pieces(counted.pieces_first_order(corner, 0.3), every.pieces_first_order(corner, 0.3), "inner corner");
  EXPECT_EQ(every.evaluations, 64u);  // kMaxSplitBranchPoints choices near the corner, all combinations
  EXPECT_LE(3 * counted.evaluations, every.evaluations) << counted.evaluations;  // 18 of 64
}

// An expression that does not say which choices reach its value, so that each choice of a piece
// beside a smooth branch point is tried flipped (Field::pieces' general way); it counts the
// evaluations either way.
class EveryFlip : public Expression {
 public:
  EveryFlip(const std::string& formula, const Box& box, const std::map<std::string, std::string>& definitions,
            bool says_which)
      : Expression(formula, {}, box, definitions), says_which_(says_which) {}
  mutable std::size_t evaluations = 0;

 protected:
  bool choices_reaching(const std::vector<std::uint8_t>& branch, std::vector<std::uint8_t>& reaches) const override {
    return says_which_ && Expression::choices_reaching(branch, reaches);
  }
  std::pair<double, Vec3> eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const override {
    ++evaluations;
    return Expression::eval_first_order(p, branch);
  }
  // A flip or a combination counts as one evaluation, as each was before Expression got them
  // from one run.
  void eval_first_order_flips(const Vec3& p, std::vector<std::uint8_t>& branch, std::span<const ChoiceStep> steps,
                              const std::function<bool(double, const Vec3&)>& hidden) const override {
    for (const ChoiceStep& step : steps) evaluations += step.flip;
    Expression::eval_first_order_flips(p, branch, steps, hidden);
  }
  void eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base, std::span<const int> split,
                                     std::vector<std::pair<double, Vec3>>& out) const override {
    evaluations += std::size_t{1} << split.size();
    Expression::eval_first_order_combinations(p, base, split, out);
  }

 private:
  bool says_which_;
};

// Beside smooth branch points (a smooth union's clamp), each choice of a piece that changes
// nothing at the point is made free. A choice whose result a later given choice discards is made
// free without an evaluation: the same pieces, bit for bit and in the same order, as flipping
// every choice, with and without Hessians, at random points near a smooth union of a sharp union
// of boxes and a ball, a hole cut sharply through it, and one sub-expression used twice; with
// fewer evaluations.
TEST(FieldPieces, ChoicesALaterChoiceDiscardsAreFreeWithoutAnEvaluation) {
  const Box box{Vec3::Constant(-1.3), Vec3::Constant(1.3)};
  const std::map<std::string, std::string> definitions = {
      {"a", "min(max(abs(x)-0.5, abs(y)-0.3, abs(z)-0.4), max(abs(x-0.3)-0.2, abs(y+0.2)-0.5, abs(z)-0.2), "
            "max(abs(x+0.4)-0.1, abs(y-0.3)-0.1, abs(z+0.3)-0.3), max(abs(x)-0.1, abs(y)-0.6, abs(z-0.1)-0.1))"},
      {"b", "hypot(x-0.4, y, z)-0.5"},
      {"h", "clamp(0.5+0.5*(b-a)/0.1, 0, 1)"}};
  const std::string formula = "max(b+(a-b)*h-0.1*h*(1-h), 0.15-hypot(x, y), -a-0.6)";
  const EveryFlip every(formula, box, definitions, false), reaching(formula, box, definitions, true);
  ASSERT_TRUE(reaching.has_pieces());
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coordinate(-0.9, 0.9);
  int beside_smooth = 0;
  for (int i = 0; i < 400; ++i) {
    const Vec3 p(coordinate(rng), coordinate(rng), coordinate(rng));
    for (const double radius : {0.05, 0.2, 0.6}) {
      const std::string where =
          "at " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + " radius " +
          std::to_string(radius);
      const auto pieces = reaching.pieces(p, radius);
      expect_same_pieces(pieces, every.pieces(p, radius), where);
      expect_same_pieces(reaching.pieces_first_order(p, radius), every.pieces_first_order(p, radius), where);
      for (const FieldPiece& q : pieces)
        if (std::count(q.branch.begin(), q.branch.end(), Field::kFreeBranch) > 0) ++beside_smooth;
    }
  }
  EXPECT_GT(beside_smooth, 100);  // the test is about pieces with free choices
  // 79,769 of 115,049: the combinations split near each point and the choices that reach the value
  // are evaluated either way.
  EXPECT_LT(4 * reaching.evaluations, 3 * every.evaluations) << reaching.evaluations << " of " << every.evaluations;
}

// Without Hessians, pieces() gives the same pieces, values and gradients (the Hessians left zero).
TEST(FieldPieces, PiecesToFirstOrderAreThePiecesWithoutTheirHessians) {
  const Expression cube = crease_expression(kCubeFormula);
  for (const Vec3& p : {Vec3(1, 0.5, 0.2), Vec3(1, 0.95, 0.2), Vec3(0.98, -0.99, 1.0)}) {
    const auto full = cube.pieces(p, 0.1), first = cube.pieces_first_order(p, 0.1);
    ASSERT_EQ(full.size(), first.size());
    for (std::size_t i = 0; i < full.size(); ++i) {
      EXPECT_EQ(first[i].branch, full[i].branch);
      EXPECT_EQ(first[i].value, full[i].value);
      EXPECT_EQ(first[i].gradient, full[i].gradient);
      EXPECT_EQ(first[i].hessian, Mat3::Zero());
    }
  }
  cube.reset_counts();
  EXPECT_EQ(cube.pieces_first_order(Vec3(1, 1, 1), 0.01).size(), 3u);
  EXPECT_EQ(cube.counts().value_gradient, 4u);
  EXPECT_EQ(cube.counts().gradient_hessian, 0u);
}

std::vector<std::vector<std::uint8_t>> branches(const std::vector<FieldPiece>& pieces) {
  std::vector<std::vector<std::uint8_t>> out;
  for (const auto& q : pieces) out.push_back(q.branch);
  return out;
}

TEST(CreaseProjection, LandsOnTheCircleWhereTwoSpheresMeet) {
  const Expression spheres = crease_expression("min(sqrt((x-0.5)^2+y^2+z^2)-1, sqrt((x+0.5)^2+y^2+z^2)-1)");
  const Vec3 start(0.05, 0.8, 0.2);
  const auto b = branches(spheres.pieces(start, 0.1));
  ASSERT_EQ(b.size(), 2u);
  // With the default tolerance (1e-10 of the box diagonal), within it.
  const double tol = 1e-10 * spheres.bounds().diagonal();
  const CreaseProjection coarse = project_to_crease(spheres, start, b);
  ASSERT_TRUE(coarse.ok()) << to_string(coarse.status);
  EXPECT_LE(coarse.residual, tol);
  EXPECT_LE(std::abs(coarse.point.x()), tol);
  EXPECT_LE(std::abs(std::hypot(coarse.point.y(), coarse.point.z()) - std::sqrt(0.75)), tol);
  // Newton's convergence is quadratic: a tighter tolerance costs a step or two.
  CreaseOptions tight;
  tight.tolerance = 1e-14;
  const CreaseProjection r = project_to_crease(spheres, start, b, tight);
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  EXPECT_LE(r.iterations, coarse.iterations + 2);
  // The circle x = 0, y^2 + z^2 = 3/4; the minimum-norm steps keep the point's direction
  // around the x axis.
  EXPECT_NEAR(r.point.x(), 0, 1e-12);
  EXPECT_NEAR(std::hypot(r.point.y(), r.point.z()), std::sqrt(0.75), 1e-12);
  EXPECT_NEAR(std::atan2(r.point.z(), r.point.y()), std::atan2(start.z(), start.y()), 1e-9);
  EXPECT_NEAR(spheres.value(r.point), 0, 1e-12);
}

TEST(CreaseProjection, LandsOnACubesEdgeAndCornerAndACylindersRim) {
  const Expression cube = crease_expression(kCubeFormula);
  const Vec3 near_edge(1.02, 0.97, 0.3);
  const auto edge = project_to_crease(cube, near_edge, branches(cube.pieces(near_edge, 0.1)));
  ASSERT_TRUE(edge.ok());
  EXPECT_LE((edge.point - Vec3(1, 1, 0.3)).norm(), 1e-12);
  const Vec3 near_corner(0.97, -1.03, 0.99);
  const auto corner_pieces = cube.pieces(near_corner, 0.1);
  ASSERT_EQ(corner_pieces.size(), 3u);
  const auto corner = project_to_crease(cube, near_corner, branches(corner_pieces));
  ASSERT_TRUE(corner.ok());
  EXPECT_LE((corner.point - Vec3(1, -1, 1)).norm(), 1e-12);

  const Expression cylinder = crease_expression("max(sqrt(x^2+y^2)-1, abs(z)-1)");
  const Vec3 near_rim(0.6, 0.75, -0.98);
  const auto rim = project_to_crease(cylinder, near_rim, branches(cylinder.pieces(near_rim, 0.1)));
  ASSERT_TRUE(rim.ok());
  EXPECT_NEAR(rim.point.z(), -1, 1e-12);
  EXPECT_NEAR(std::hypot(rim.point.x(), rim.point.y()), 1, 1e-12);
}

// Given the pieces' values and gradients at the start, the projection makes the same steps
// without evaluating them there again, and reports the gradients of its last evaluation.
TEST(CreaseProjection, StartsFromGivenEvaluationsAndReportsTheLastGradients) {
  const Expression spheres = crease_expression("min(hypot(x-0.5,y,z)-1, hypot(x+0.5,y,z)-1)");
  const Vec3 start(0.1, 0.7, 0.3);
  const auto near = spheres.pieces(start, 0.5);
  ASSERT_EQ(near.size(), 2u);
  const auto b = branches(near);
  const std::array<std::pair<double, Vec3>, 2> at_start{std::pair{near[0].value, near[0].gradient},
                                                        std::pair{near[1].value, near[1].gradient}};
  const CreaseProjection plain = project_to_crease(spheres, start, b);
  spheres.reset_counts();
  const CreaseProjection given = project_to_crease(spheres, start, b, at_start);
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(given.point, plain.point);
  EXPECT_EQ(given.iterations, plain.iterations);
  EXPECT_EQ(spheres.counts().value_gradient, 2u * static_cast<std::uint64_t>(plain.iterations));
  for (std::size_t i = 0; i < 2; ++i) EXPECT_EQ(given.gradients[i], spheres.piece_first_order(given.point, b[i]).second);
  EXPECT_THROW(project_to_crease(spheres, start, b, std::span(at_start).first(1)), InvalidInputError);
}

TEST(CreaseProjection, ReportsTangentPiecesAndRefusesOtherCounts) {
  // Two planes that are parallel (x = 0 and x = 0.5): no crease between them.
  const Expression slab = crease_expression("max(x-0.5, -x)");
  const auto b = branches(slab.pieces(Vec3(0.25, 0, 0), 1));
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(project_to_crease(slab, Vec3(0.25, 0, 0), b).status, CreaseStatus::DependentGradients);
  EXPECT_THROW(project_to_crease(slab, Vec3::Zero(), std::vector<std::vector<std::uint8_t>>{b[0]}), InvalidInputError);
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

TEST(CreaseCurves, ACubeHasTwelveEdgesBetweenEightCorners) {
  const Expression cube = crease_expression(kCubeFormula);
  const CreaseTracingResult r = trace_creases(cube);
  EXPECT_EQ(r.curves.size(), 12u);
  EXPECT_EQ(r.corners.size(), 8u);
  EXPECT_EQ(r.stops, 0u);
  const double tol = 1e-10 * cube.bounds().diagonal() * 20;
  for (const CreaseCurve& c : r.curves) {
    EXPECT_FALSE(c.closed);
    EXPECT_TRUE(c.starts_at_corner && c.ends_at_corner);
    // From corner to corner: length 2 along one axis.
    EXPECT_NEAR((c.points.back() - c.points.front()).norm(), 2, tol);
    for (const Vec3& p : c.points) {
      int on_faces = 0;
      for (int a = 0; a < 3; ++a) on_faces += std::abs(std::abs(p[a]) - 1) <= tol;
      EXPECT_GE(on_faces, 2) << p.transpose();
    }
  }
  for (const Vec3& q : r.corners) EXPECT_LE((q.cwiseAbs() - Vec3::Ones()).norm(), tol) << q.transpose();
}

TEST(CreaseCurves, AMengerSpongeOfLevelOneHasItsSeventyTwoEdges) {
  // A cube with three square holes crossing: 12 cube edges, 4 rim edges around each of the 6
  // openings, 4 concave edges along each of the 6 half-tunnels and the 12 convex edges of the
  // cavity where they cross; corners: the cube's 8, 4 at each opening, the cavity's 8. Where an
  // opening's corner is, a hole's wall and a crossing hole's face are one plane from two
  // branches: pairs of pieces that meet only at the corner are no crease (they were 5 curves of
  // a single point, which the layout refused).
  const Expression menger = crease_expression(
      "max(max(abs(x), abs(y), abs(z)) - 1, -min(max(abs(x), abs(y)) - 0.4, max(abs(y), abs(z)) - 0.4, "
      "max(abs(x), abs(z)) - 0.4))",
      1.3);
  const CreaseTracingResult r = trace_creases(menger);
  // The same curves from a grid sampled before (the adaptive polygonizer's seed grid).
  const SeedGrid grid = sample_seed_grid(menger, SeedOptions{});
  CreaseTracingOptions given;
  given.grid = &grid;
  const CreaseTracingResult again = trace_creases(menger, given);
  ASSERT_EQ(again.curves.size(), r.curves.size());
  for (std::size_t i = 0; i < r.curves.size(); ++i) EXPECT_EQ(again.curves[i].points, r.curves[i].points);
  EXPECT_EQ(r.curves.size(), 72u);
  EXPECT_EQ(r.corners.size(), 40u);
  EXPECT_EQ(r.stops, 0u);
  for (const CreaseCurve& c : r.curves) {
    EXPECT_FALSE(c.closed);
    EXPECT_TRUE(c.starts_at_corner && c.ends_at_corner);
    const double length = (c.points.back() - c.points.front()).norm();
    EXPECT_TRUE(std::abs(length - 2) < 1e-6 || std::abs(length - 0.8) < 1e-6 || std::abs(length - 0.6) < 1e-6)
        << length;
  }
}

// Equal pipes of radius 0.5 whose creases meet where the pipes are tangent, at +-0.5 along
// `axis`: no stop, those two corners (to `within`), and `arcs` open curves, each from one
// corner to the other, besides the rims on the box's faces.
void expect_arcs_between_tangent_corners(const CreaseTracingResult& r, int axis, double within, std::size_t arcs) {
  EXPECT_EQ(r.stops, 0u);
  ASSERT_EQ(r.corners.size(), 2u);
  const Vec3 tangent = 0.5 * Vec3::Unit(axis);
  for (const Vec3& c : r.corners) EXPECT_LT((c.cwiseAbs() - tangent).norm(), within) << c.transpose();
  std::size_t open = 0;
  for (const CreaseCurve& c : r.curves) {
    if (c.closed) continue;  // the rims on the box's faces
    ++open;
    EXPECT_TRUE(c.starts_at_corner && c.ends_at_corner);
    EXPECT_NEAR(std::abs(c.points.front()[axis] - c.points.back()[axis]), 1.0, 1e-3);
  }
  EXPECT_EQ(open, arcs);
}

TEST(CreaseCurves, CreasesThatCrossWhereTheirPiecesAreTangentMeetAtACorner) {
  // Two equal pipes crossing: the ellipses where they meet (in the planes x = y and x = -y) cross
  // at (0, 0, +-0.5), where the pipes are tangent. Four arcs, each from one crossing to the other.
  const Expression pipes = crease_expression("min(hypot(y, z) - 0.5, hypot(x, z) - 0.5)", 1);
  expect_arcs_between_tangent_corners(trace_creases(pipes), 2, 1e-3, 4);
}

TEST(CreaseCurves, TwoCreasesEndingWhereTheirPiecesAreTangentMeetAtACorner) {
  // A tee of two equal pipes: the z pipe, from z = 0 up, meets the x pipe along two half
  // ellipses (in the planes x = z and x = -z) that end at (0, +-0.5, 0), where the pipes are
  // tangent. Two stops there, one of each arc: a corner, as where four arcs cross.
  const Expression tee = crease_expression("min(hypot(y, z) - 0.5, max(hypot(x, y) - 0.5, -z))", 1);
  // The corner is the mean of the two stops, each short of it by up to a min_spacing (0.0017
  // here), from two directions at right angles.
  expect_arcs_between_tangent_corners(trace_creases(tee), 1, 2e-3, 2);
}

TEST(CreaseCurves, LoopsOfACylindersRimsTwoSpheresAndABoxMinusASphere) {
  const Expression cylinder = crease_expression("max(sqrt(x^2+y^2)-1, abs(z)-1)");
  const CreaseTracingResult rims = trace_creases(cylinder);
  ASSERT_EQ(rims.curves.size(), 2u);
  for (const CreaseCurve& c : rims.curves) {
    EXPECT_TRUE(c.closed);
    for (const Vec3& p : c.points) {
      EXPECT_NEAR(std::abs(p.z()), 1, 1e-9);
      EXPECT_NEAR(std::hypot(p.x(), p.y()), 1, 1e-9);
    }
    // Spaced at most max_spacing (0.02 of the diagonal) apart, all the way round.
    double length = 0;
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      const double d = (c.points[(i + 1) % c.points.size()] - c.points[i]).norm();
      EXPECT_LE(d, 0.02 * cylinder.bounds().diagonal() * 1.01);
      length += d;
    }
    EXPECT_NEAR(length, 2 * std::numbers::pi, 0.01);
  }
  EXPECT_TRUE(rims.corners.empty());

  const Expression spheres = crease_expression("min(sqrt((x-0.5)^2+y^2+z^2)-1, sqrt((x+0.5)^2+y^2+z^2)-1)");
  const CreaseTracingResult circle = trace_creases(spheres);
  ASSERT_EQ(circle.curves.size(), 1u);
  EXPECT_TRUE(circle.curves[0].closed);

  // A box with a ball of radius 1.2 taken out: the ball opens a round hole in each face (radius
  // sqrt(1.2^2 - 1)) and leaves the edges and corners whole.
  const Expression carved = crease_expression("max(max(abs(x),max(abs(y),abs(z)))-1, 1.2-sqrt(x^2+y^2+z^2))");
  const CreaseTracingResult holes = trace_creases(carved);
  std::size_t loops = 0;
  for (const CreaseCurve& c : holes.curves) {
    loops += c.closed;
    if (!c.closed) continue;
    for (const Vec3& p : c.points) EXPECT_NEAR(p.norm(), 1.2, 1e-9);
  }
  EXPECT_EQ(loops, 6u);
  EXPECT_EQ(holes.curves.size(), 18u);
  EXPECT_EQ(holes.corners.size(), 8u);
}

// A rod of radius r through a ball of radius 1 (cdp.sdf's sphere(1) | capsule, a pin): its two
// rims are circles of radius r at |z| = sqrt(1 - r^2), each traced once round, however much
// shorter than two max_spacing (0.02 of the diagonal, 0.28 here) it is. The walk closed a loop
// only after travelling two max_spacing, so a rim shorter than that went round more than once
// (in polygonize, r = 0.02 in a box of diagonal 5.2: a rim 0.126 long traced as 0.251), and the
// patches meshed from it tangled. r = 0.1 is longer than that.
TEST(CreaseCurves, ARimShorterThanTwoStepsIsTracedOnceRound) {
  for (const double r : {0.1, 0.02, 0.01}) {
    SCOPED_TRACE(r);
    const Expression pin = crease_expression(
        "min(sqrt(x^2+y^2+z^2)-1, sqrt(x^2+y^2+(z-clamp(z,-1.5,1.5))^2)-" + std::to_string(r) + ")");
    const CreaseTracingResult rims = trace_creases(pin);
    ASSERT_EQ(rims.curves.size(), 2u);
    for (const CreaseCurve& c : rims.curves) {
      EXPECT_TRUE(c.closed);
      double length = 0;
      for (std::size_t i = 0; i < c.points.size(); ++i) {
        const Vec3& p = c.points[i];
        EXPECT_NEAR(std::hypot(p.x(), p.y()), r, 1e-9);
        EXPECT_NEAR(std::abs(p.z()), std::sqrt(1 - r * r), 1e-9);
        length += (c.points[(i + 1) % c.points.size()] - p).norm();
      }
      // Chords of a circle: up to 1 % short of it at r = 0.01 (steps of min_spacing); a rim traced
      // twice would be twice as long.
      EXPECT_NEAR(length, 2 * std::numbers::pi * r, 0.02 * 2 * std::numbers::pi * r);
    }
  }
}

// A table top 0.05 thick (|x| <= 1, |y| <= 0.5, 0.695 <= z <= 0.745) with a leg under its middle
// reaching 0.005 into it. The top's four vertical edges are 0.05 long, under a cell of the grid
// the leg's box makes (0.075): two of them crossed no grid edge near enough and were not traced,
// and the patch boundaries broke off at their corners. Every crease leaving a corner is traced
// from it: the top's 12 edges, the leg's 8 and the 4 where its sides meet the top's underside.
TEST(CreaseCurves, AnEdgeShorterThanAGridCellBetweenTwoCornersIsTracedFromThem) {
  const Expression table("min(max(abs(x)-1, abs(y)-0.5, abs(z-0.72)-0.025), max(abs(x)-0.05, abs(y)-0.05, abs(z-0.35)-0.35))",
                         Box{Vec3(-1.2, -0.7, -0.2), Vec3(1.2, 0.7, 0.945)});
  const CreaseTracingResult r = trace_creases(table);
  EXPECT_EQ(r.curves.size(), 24u);
  EXPECT_EQ(r.corners.size(), 16u);
  EXPECT_EQ(r.stops, 0u);
  int vertical_top_edges = 0;
  for (const CreaseCurve& c : r.curves) {
    const Vec3 &a = c.points.front(), &b = c.points.back();
    if (std::abs(std::abs(a.x()) - 1) < 1e-9 && std::abs(std::abs(a.y()) - 0.5) < 1e-9 && (a - b).norm() > 0.049 &&
        std::abs(a.z() - b.z()) > 0.049)
      ++vertical_top_edges;
  }
  EXPECT_EQ(vertical_top_edges, 4);
}

// Two unit boxes sharing a face (x = 0.5, |y|, |z| <= 0.5): their union's field is -|x - 0.5|
// across it, zero on it, and the pieces there face opposite ways. That face is no surface: no
// crease lies on it or along its rim (where each box's edge runs on, the union's faces are
// flat). The union's creases are the 2 x 1 x 1 box's twelve edges, the four long ones each in two
// pieces (one box's, then the other's) meeting at x = 0.5. A crease was traced as a single point
// on the common face, and the layout failed.
TEST(CreaseCurves, TwoSolidsTouchingAlongAFaceHaveNoCreaseOnIt) {
  const Expression boxes("min(max(abs(x)-0.5, abs(y)-0.5, abs(z)-0.5), max(abs(x-1)-0.5, abs(y)-0.5, abs(z)-0.5))",
                         Box{Vec3(-0.7, -0.7, -0.7), Vec3(1.7, 0.7, 0.7)});
  const CreaseTracingResult r = trace_creases(boxes);
  EXPECT_EQ(r.curves.size(), 16u);
  EXPECT_EQ(r.stops, 0u);
  for (const CreaseCurve& c : r.curves)
    for (const Vec3& p : c.points) {
      // On an edge of the long box: two of its coordinates on its faces.
      const int on = (std::abs(p.x() + 0.5) < 1e-9 || std::abs(p.x() - 1.5) < 1e-9) +
                     (std::abs(std::abs(p.y()) - 0.5) < 1e-9) + (std::abs(std::abs(p.z()) - 0.5) < 1e-9);
      EXPECT_GE(on, 2) << p.transpose();
    }
}

// A unit box minus a unit box touching its face x = 0.5 from outside (a cutter placed flush):
// the difference is the first box. The cutter's side faces, negated, meet the box's edges on that
// face, but lie off the box's surface on either side of them: each of those four edges was traced
// twice (its pieces the box's, then the cutter's), and the layout failed.
TEST(CreaseCurves, ACutterFlushWithAFaceLeavesEachEdgeOnce) {
  const Expression cut("max(max(abs(x)-0.5, abs(y)-0.5, abs(z)-0.5), -max(abs(x-1)-0.5, abs(y)-0.5, abs(z)-0.5))",
                       Box{Vec3(-0.7, -0.7, -0.7), Vec3(0.7, 0.7, 0.7)});
  const CreaseTracingResult r = trace_creases(cut);
  EXPECT_EQ(r.curves.size(), 12u);
  EXPECT_EQ(r.corners.size(), 8u);
  EXPECT_EQ(r.stops, 0u);
}

// Two overlapping spheres on a bar (radius 0.85 at x = -0.5 and 0.5; the bar |x| <= 1.2,
// -1.15 <= y <= -0.65, |z| <= 0.25). Where the spheres' seam meets the bar's top face, a face
// 0.025 wide is left between three corners on each side: the seam's (0, -0.65, +-sqrt(0.05))
// and the two where the bar's edge leaves one sphere and enters the other (+-(0.5 - sqrt(0.2375)),
// -0.65, +-0.25). A walk from one of them towards the next took the corner it started from for
// the only one near, stepped past the next and stopped (4 stops at resolution 64); and a walk
// jumped to a corner 0.23 ahead along a sphere's arc on the bar's side, a chord that strayed
// from the arc, so the arc was traced three times. Every crease once: the seam; the arcs of
// each sphere on the top face (2 short ones each by the seam, 1 each at the bar's ends) and on
// the two sides (2 each); the top edges' pieces between the spheres (2) and at the ends (4);
// the end faces' edges (8); the bottom's long edges (2).
TEST(CreaseCurves, TwoSpheresOnABarHaveEveryCornerOfTheFaceBetweenThem) {
  const Expression bar = crease_expression(test::kSpheresOnABar, 1.7);
  CreaseTracingOptions o;
  o.resolution = 64;
  const CreaseTracingResult r = trace_creases(bar, o);
  EXPECT_EQ(r.stops, 0u);
  EXPECT_EQ(r.corners.size(), 18u);
  EXPECT_EQ(r.curves.size(), 27u);
  for (const CreaseCurve& c : r.curves) EXPECT_TRUE(c.closed || (c.starts_at_corner && c.ends_at_corner));
  const double seam = std::sqrt(0.05), edge = 0.5 - std::sqrt(0.2375);
  for (const Vec3& corner : {Vec3(0, -0.65, seam), Vec3(0, -0.65, -seam), Vec3(edge, -0.65, 0.25),
                             Vec3(-edge, -0.65, 0.25), Vec3(edge, -0.65, -0.25), Vec3(-edge, -0.65, -0.25)}) {
    double nearest = 1;
    for (const Vec3& q : r.corners) nearest = std::min(nearest, (q - corner).norm());
    EXPECT_LT(nearest, 1e-8) << corner.transpose();
  }
}

TEST(CreaseCurves, TheGyroidAndBarthBallsRimsAreAllFoundOnce) {
  // The creases are where the gyroid (Barth's sextic) meets the clipping sphere. How many curves
  // that is was counted independently: the sign of the gyroid (sextic) on a 2000 x 4000
  // latitude-longitude grid of the sphere has 10 (21) connected regions, and disjoint closed
  // curves on a sphere leave one region more than there are curves.
  struct Ball {
    std::string formula;
    double half, radius;
    std::size_t curves;
  };
  const Ball balls[] = {
      {"max(sin(4*x)*cos(4*y)+sin(4*y)*cos(4*z)+sin(4*z)*cos(4*x), x^2+y^2+z^2-4)", 2.2, 2, 9},
      {"max(4*(2.618034*x^2-y^2)*(2.618034*y^2-z^2)*(2.618034*z^2-x^2)-4.236068*(x^2+y^2+z^2-1)^2+0.01, "
       "x^2+y^2+z^2-3.5)",
       2.1, std::sqrt(3.5), 20},
  };
  for (const Ball& b : balls) {
    const Expression e = crease_expression(b.formula, b.half);
    const CreaseTracingResult r = trace_creases(e);
    EXPECT_EQ(r.curves.size(), b.curves) << b.formula;
    EXPECT_EQ(r.stops, 0u);
    EXPECT_TRUE(r.corners.empty());
    for (const CreaseCurve& c : r.curves) {
      EXPECT_TRUE(c.closed);
      // On both pieces to within the Newton tolerance (first-order distance |F_i| / |grad F_i|).
      const double tol = 1e-10 * e.bounds().diagonal();
      for (const Vec3& p : c.points) {
        const auto pieces = e.pieces(p, 1e-6);
        ASSERT_EQ(pieces.size(), 2u);
        for (const FieldPiece& q : pieces) EXPECT_LE(std::abs(q.value) / q.gradient.norm(), tol);
        EXPECT_NEAR(p.norm(), b.radius, 2 * tol);
      }
    }
  }
}

// The fields SDF code writes: rounded primitives and smooth unions are C1 where their min, max
// and clamps switch, so they have no crease; a sharp difference on top of them still has.
const char* kRoundedBoxFormula = "sqrt(max(abs(x)-0.6,0)^2+max(abs(y)-0.4,0)^2+max(abs(z)-0.3,0)^2)-0.15";
// Inigo Quilez's polynomial smooth minimum of the rounded box a and a sphere b, radius 0.2.
Expression smooth_union(const std::string& outer = "u") {
  return Expression(outer, {}, Box{Vec3::Constant(-1.2), Vec3::Constant(1.2)},
                    {{"a", kRoundedBoxFormula},
                     {"b", "sqrt((x-0.5)^2+(y-0.3)^2+z^2)-0.45"},
                     {"h", "clamp(0.5+0.5*(b-a)/0.2,0,1)"},
                     {"u", "b + h*(a-b) - 0.2*h*(1-h)"}});
}

using Kind = Field::BranchKind;

TEST(BranchKinds, RoundedBoxesAndSmoothUnionsHaveNoCrease) {
  // Branch points in program order: abs(x), max, abs(y), max, abs(z), max. The abs switch where
  // the max hides them (|x| < 0.6 at x = 0).
  const Expression box(kRoundedBoxFormula, {}, Box{Vec3::Constant(-1.1), Vec3::Constant(1.1)});
  EXPECT_EQ(box.branch_kinds(),
            (std::vector<Kind>{Kind::Hidden, Kind::Smooth, Kind::Hidden, Kind::Smooth, Kind::Hidden, Kind::Smooth}));
  EXPECT_FALSE(box.has_pieces());
  // On the rounded edge, right where max(|x| - 0.6, 0) switches: one piece, free there.
  const Vec3 on_edge(0.6, 0.4 + 0.15, 0.1);
  const auto edge = box.pieces(on_edge, 0.1);
  ASSERT_EQ(edge.size(), 1u);
  EXPECT_EQ(edge[0].branch, (std::vector<std::uint8_t>(6, Field::kFreeBranch)));
  // A free piece is the field itself wherever it is evaluated.
  for (const Vec3& q : {Vec3(-0.7, 0.5, 0.2), Vec3(0.1, -0.2, 0.44), Vec3(0.65, 0.45, 0.35)})
    EXPECT_EQ(box.piece(q, edge[0].branch).value, box.value(q));
  EXPECT_TRUE(trace_creases(box).curves.empty());

  const Expression blend = smooth_union();
  for (const Kind k : blend.branch_kinds()) EXPECT_NE(k, Kind::Creased);
  EXPECT_FALSE(blend.has_pieces());
}

TEST(BranchKinds, ARoundedBoxWrittenWithItsCoreHasNoCreaseAndNoPieceThatLeavesIt) {
  // The rounded box as cdp.sdf writes it (length(max(q, 0)) + min(max(q), 0) - r in one hypot).
  // Its max(q) switches along the sharp edges of the core, where the min takes max(q), inside
  // the surface; from a sample in the core, that branch fixed, the switch met the core's own
  // zero set and looked creased. It is hidden wherever the surface is: with the cylinder taken
  // out, the body's piece is the field itself on the rounded edges, not a prism through them.
  const std::map<std::string, std::string> d = {{"q0", "abs(x)-0.7"}, {"q1", "abs(y)-0.4"}, {"q2", "abs(z)-0.3"},
                                                {"m", "min(max(q0,q1,q2),0)"},
                                                {"r", "hypot(max(q0,0),max(q1,0),max(q2,0),m)+2*m-0.1"}};
  const Box box{Vec3::Constant(-1), Vec3::Constant(1)};
  const Expression rounded("r", {}, box, d);
  for (const Kind k : rounded.branch_kinds()) EXPECT_NE(k, Kind::Creased);
  EXPECT_FALSE(rounded.has_pieces());
  const Expression drilled("max(r, 0.2-hypot(x,y))", {}, box, d);
  ASSERT_TRUE(drilled.has_pieces());
  EXPECT_EQ(drilled.branch_kinds().back(), Kind::Creased);
  const auto body = drilled.pieces(Vec3(0.5, 0.1, 0.4), 0.05);
  ASSERT_EQ(body.size(), 1u);
  for (const Vec3& q : {Vec3(-0.62, -0.51, -0.29), Vec3(0.75, 0.45, 0.35), Vec3(0.1, -0.5, -0.4)})
    EXPECT_EQ(drilled.piece(q, body[0].branch).value, drilled.value(q)) << q.transpose();
}

TEST(BranchKinds, TheFarSideOfAC1SeamIsTheSurfaceBeyondItContinuedToThePoint) {
  // On the rounded box's face y = 0.55, 0.05 from where max(|z| - 0.3, 0) switches and the face
  // rounds into the edge of radius 0.15 around the line y = 0.4, z = 0.3: beyond the seam the
  // field is the distance from that line minus 0.15, continued to the point a cylinder of radius
  // hypot(0.15, 0.05) there.
  const Expression box(kRoundedBoxFormula, {}, Box{Vec3::Constant(-1.1), Vec3::Constant(1.1)});
  const Vec3 p(0, 0.55, 0.25);
  const auto sides = box.smooth_sides(p, 0.1);
  ASSERT_EQ(sides.size(), 1u);
  EXPECT_NEAR(sides[0].distance, 0.05, 1e-12);
  const Curvature c = curvature_from_derivatives(sides[0].piece.gradient, sides[0].piece.hessian);
  EXPECT_NEAR(c.min_radius, std::hypot(0.15, 0.05), 1e-9);
  EXPECT_NEAR(sides[0].piece.value, std::hypot(0.15, 0.05) - 0.15, 1e-12);
  // The seam is beyond reach at 0.04, and from the face's middle (0.3 away; the switch of
  // max(|y| - 0.4, 0) lies 0.15 inside the solid there).
  EXPECT_TRUE(box.smooth_sides(p, 0.04).empty());
  EXPECT_TRUE(box.smooth_sides(Vec3(0, 0.55, 0), 0.12).empty());
  // Sharp booleans have no C1 seam.
  EXPECT_TRUE(crease_expression(kCubeFormula).smooth_sides(Vec3(1, 0.99, 0), 1).empty());
}

TEST(BranchKinds, EachFaceAtACreaseSeesItsOwnSeams) {
  // A box minus a cylinder along z with a fillet (the smooth difference's clamp): on the face
  // z = -0.75 the fillet begins where hypot(x, y) = 0.6. At (0, -0.75, -0.75), on the box's edge,
  // the field takes one face's branch of the box's max, and with it sees only that face's seam.
  // On a piece, each face sees its own, as the field does just inside that face.
  const std::map<std::string, std::string> d = {{"d0", "max(abs(x)-0.75,abs(y)-0.75,abs(z)-0.75)"},
                                                {"d1", "hypot(x,y)-0.5"},
                                                {"h", "clamp(0.5-(d1+d0)*5,0,1)"}};
  const Expression part("d0-(d1+d0)*h+0.1*h*(1-h)", {}, Box{Vec3::Constant(-0.9), Vec3::Constant(0.9)}, d);
  ASSERT_TRUE(part.has_pieces());
  const Vec3 p(0, -0.75, -0.75);
  const auto pieces = part.pieces(p, 1e-6);
  ASSERT_EQ(pieces.size(), 2u);
  constexpr double kInside = 1e-7;
  int seen = 0;
  for (const FieldPiece& piece : pieces) {
    const bool bottom = piece.gradient.z() < -0.5;  // the face z = -0.75; else y = -0.75
    const auto sides = part.smooth_sides(p, 0.5, piece.branch);
    ASSERT_EQ(sides.size(), 1u);
    // The switch d1 + d0 = 0.1 lies 0.15 away along the gradient of d1 + d0: (0, -1, -1) on the
    // bottom, (0, -2, 0) on the side. Beyond it the clamp is 0.5 - 5 (d1 + d0) = -0.75 at p: the
    // blend's value there 0.25 * 0.75 - 0.1 * 0.75 * 1.75 on both faces.
    EXPECT_NEAR(sides[0].distance, bottom ? 0.15 / std::sqrt(2.0) : 0.075, 1e-12);
    EXPECT_NEAR(sides[0].piece.value, 0.25 * 0.75 - 0.1 * 0.75 * 1.75, 1e-12);
    const Vec3 inside = p + kInside * (bottom ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
    const auto beside = part.smooth_sides(inside, 0.5);
    ASSERT_EQ(beside.size(), 1u);
    EXPECT_NEAR(sides[0].distance, beside[0].distance, 10 * kInside);
    EXPECT_LT((sides[0].piece.gradient - beside[0].piece.gradient).norm(), 10 * kInside);
    EXPECT_LT((sides[0].piece.hessian - beside[0].piece.hessian).norm(), 100 * kInside);
    // Where the far side begins: the switch's point nearest p, (0, -0.675, -0.675) on the bottom,
    // (0, -0.675, -0.75) on the side, where the clamp's argument is 0 and the blend
    // d0 + 2.5 s^2 - 0.5 s + 0.025 (s = d1 + d0 = 0.1) has the Hessian 5 grad s grad s^T (the
    // cylinder's bend cancels there) and the gradient grad d0. On the bottom grad s = (0, -1, -1):
    // a bend of 5 across the seam, the fillet's radius 0.2 (continued to p, 1.38). On the side
    // grad s = (0, -2, 0) is the face's normal: the blend begins flat.
    const auto begins = part.smooth_sides(p, 0.5, piece.branch, Field::SeamSideAt::Seam);
    ASSERT_EQ(begins.size(), 1u);
    EXPECT_EQ(begins[0].distance, sides[0].distance);
    EXPECT_NEAR(begins[0].piece.value, -0.075, 1e-12);  // d0 there, off the surface
    const Curvature at_seam = curvature_from_derivatives(begins[0].piece.gradient, begins[0].piece.hessian);
    if (bottom) {
      EXPECT_NEAR(at_seam.min_radius, 0.2, 1e-9);
      EXPECT_GT(curvature_from_derivatives(sides[0].piece.gradient, sides[0].piece.hessian).min_radius, 1.3);
    } else {
      EXPECT_GT(at_seam.min_radius, 1e9);
    }
    seen |= bottom ? 1 : 2;
  }
  EXPECT_EQ(seen, 3);
  // The field itself, at the same point, sees one of the two.
  EXPECT_EQ(part.smooth_sides(p, 0.5).size(), 1u);
  // A compiled model of the same formula (its jets record the branches a piece forces) sees the
  // same: its branch points are numbered as the expression's (abs, abs, max, abs, max; the
  // clamp's max and min).
  const auto filleted_hole = [](const auto& x, const auto& y, const auto& z) {
    using T = std::decay_t<decltype(x)>;
    using std::abs, std::max, std::min, std::sqrt;
    const T d0 = max(max(abs(x) - 0.75, abs(y) - 0.75), abs(z) - 0.75);
    const T d1 = sqrt(x * x + y * y) - 0.5;
    const T h = min(max(0.5 - (d1 + d0) * 5.0, T(0.0)), T(1.0));
    return T(d0 - (d1 + d0) * h + 0.1 * h * (1.0 - h));
  };
  const FunctionField<decltype(filleted_hole)> compiled("filleted_hole", filleted_hole, part.bounds());
  for (const FieldPiece& piece : pieces) {
    const auto a = compiled.smooth_sides(p, 0.5, piece.branch), b = part.smooth_sides(p, 0.5, piece.branch);
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    EXPECT_NEAR(a[0].distance, b[0].distance, 1e-14);
    EXPECT_NEAR(a[0].piece.value, b[0].piece.value, 1e-14);
    EXPECT_LT((a[0].piece.gradient - b[0].piece.gradient).norm(), 1e-13);
    EXPECT_LT((a[0].piece.hessian - b[0].piece.hessian).norm(), 1e-12);
  }
}

TEST(BranchKinds, SharpBooleansStayCreasedBesideSmoothOnes) {
  // The cube (abs(x), abs(y), abs(z), the inner max, the outer one): its max are creases, and
  // classifying them is counted, once.
  const Expression cube = crease_expression(kCubeFormula);
  cube.reset_counts();
  EXPECT_TRUE(cube.has_pieces());
  const std::uint64_t classified = cube.counts().value_gradient;
  EXPECT_GT(classified, 0u);
  EXPECT_EQ(cube.branch_kinds()[3], Kind::Creased);
  EXPECT_EQ(cube.branch_kinds()[4], Kind::Creased);
  EXPECT_EQ(cube.counts().value_gradient, classified);
  // The smooth union minus a cylinder along z: the last max is the only crease, two rims.
  const Expression drilled = smooth_union("max(u, 0.2-sqrt(x^2+y^2))");
  const auto& kinds = drilled.branch_kinds();
  ASSERT_EQ(kinds.size(), 9u);
  EXPECT_EQ(kinds.back(), Kind::Creased);
  for (std::size_t k = 0; k + 1 < kinds.size(); ++k) EXPECT_NE(kinds[k], Kind::Creased) << k;
  EXPECT_TRUE(drilled.has_pieces());
  const CreaseTracingResult traced = trace_creases(drilled);
  ASSERT_EQ(traced.curves.size(), 2u);
  for (const CreaseCurve& c : traced.curves) {
    EXPECT_TRUE(c.closed);
    for (const Vec3& p : c.points) {
      EXPECT_NEAR(std::hypot(p.x(), p.y()), 0.2, 1e-8);
      EXPECT_NEAR(drilled.value(p), 0, 1e-8);
    }
    // The body's piece is free at every branch point but the cylinder's: the field itself where
    // the cylinder does not cut, on both rims and far from them.
    const std::vector<std::uint8_t>& body = drilled.piece(c.points[0], c.pieces[0]).gradient.z() != 0 ? c.pieces[0] : c.pieces[1];
    for (const Vec3& q : {Vec3(0.7, 0.5, 0.3), Vec3(-0.7, -0.5, -0.3), Vec3(0.5, 0.3, 0.44)})
      EXPECT_EQ(drilled.piece(q, body).value, drilled.value(q)) << q.transpose();
  }
}

TEST(BranchKinds, ASwitchMetMostlyBehindASmoothBooleansOtherShapeIsNoC1Seam) {
  // fogleman/sdf's box(1) | box(0.76).translate((-0.33, 0.53, 0.48)).k(0.04): the small box's
  // switch between its z face and its sides meets the surface at its top and bottom edges, and
  // across the big box's faces, where the blend's clamp multiplies the small box by 0: there the
  // two sides' normals agree. The samples that met it only there took it for a C1 seam; it was
  // never split, and the walks along the small box's vertical edges stopped a step short of its
  // corners. Every min, max and abs of the two boxes is a crease or hidden; only the clamp's two
  // branch points are smooth.
  const Expression field("d1 + (d0 - d1)*h - 0.04*h*(1 - h)", {}, Box{Vec3(-0.899, -0.689, -0.689), Vec3(0.689, 1.099, 1.049)},
                         {{"d0", "max(abs(x) - 0.5, abs(y) - 0.5, abs(z) - 0.5)"},
                          {"d1", "max(abs(x + 0.33) - 0.38, abs(y - 0.53) - 0.38, abs(z - 0.48) - 0.38)"},
                          {"h", "clamp(0.5 + (d1 - d0)*12.5, 0, 1)"}});
  const auto& kinds = field.branch_kinds();
  ASSERT_EQ(kinds.size(), 12u);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), Kind::Smooth), 2);
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  for (const Vec3& t : {Vec3(-0.71, 0.91, 0.86), Vec3(-0.71, 0.91, 0.1), Vec3(0.05, 0.91, 0.86), Vec3(-0.71, 0.15, 0.86)}) {
    EXPECT_TRUE(has_corner(r, t)) << t.transpose();
  }
}

TEST(BranchKinds, ACubesPiecesAreAsTheyWere) {
  // Without smooth branch points nothing is free: the pieces keep every branch fixed.
  const Expression cube = crease_expression(kCubeFormula);
  for (const FieldPiece& q : cube.pieces(Vec3(0.98, -0.99, 1.0), 0.05))
    for (const std::uint8_t b : q.branch) EXPECT_NE(b, Field::kFreeBranch);
}

TEST(CreaseCurves, SmoothFieldsHaveNone) {
  EXPECT_TRUE(trace_creases(Sphere(Vec3::Zero(), 1)).curves.empty());
  EXPECT_TRUE(trace_creases(crease_expression("x^2+y^2+z^2-1")).curves.empty());
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// A compiled model (autodiff_field.h) written with min, max and abs has the same pieces as the
// expression of the same formula: its jets record and force the branches as the interpreter does.
TEST(CompiledPieces, ACompiledCappedCylinderHasTheExpressionsPieces) {
  const auto compiled = compiled_models().at("capped_cylinder")();
  const Expression e = crease_expression("max(sqrt(x^2+y^2)-1, abs(z)-1)", 1.5);
  EXPECT_TRUE(compiled->has_pieces());
  EXPECT_FALSE(compiled_models().at("tanglecube")()->has_pieces());
  const Vec3 points[] = {{0.2, 0.1, 1.0}, {0.99, 0.05, 0.5}, {0.6, 0.8, 0.98}, {0.7071, -0.7071, -1.0}, {0.1, 0.2, 0}};
  std::size_t creased = 0;
  for (const Vec3& p : points) {
    const auto a = compiled->pieces(p, 0.05), b = e.pieces(p, 0.05);
    ASSERT_EQ(a.size(), b.size()) << p.transpose();
    creased += a.size() > 1;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].branch, b[i].branch);
      EXPECT_NEAR(a[i].value, b[i].value, 1e-14);
      EXPECT_LE((a[i].gradient - b[i].gradient).norm(), 1e-13);
      EXPECT_LE((a[i].hessian - b[i].hessian).norm(), 1e-12);
      // The piece evaluated elsewhere with its branches fixed.
      const Vec3 far(0.1, -0.4, 0.3);
      const FieldPiece fa = compiled->piece(far, a[i].branch), fb = e.piece(far, b[i].branch);
      EXPECT_NEAR(fa.value, fb.value, 1e-14);
      EXPECT_LE((fa.gradient - fb.gradient).norm(), 1e-13);
    }
  }
  EXPECT_EQ(creased, 2u);  // near the rims: the side and a cap
  EXPECT_THROW(compiled->piece(Vec3::Zero(), {0}), InvalidInputError);
  // Traced from its pieces: the two rims.
  const CreaseTracingResult r = trace_creases(*compiled);
  EXPECT_EQ(r.curves.size(), 2u);
  for (const CreaseCurve& c : r.curves) {
    EXPECT_TRUE(c.closed);
    for (const Vec3& q : c.points) EXPECT_NEAR(std::hypot(q.x(), q.y()), 1.0, 1e-9);
  }
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// A box with a ball blended onto its edge x = y = 0.75 (Inigo Quilez's polynomial smooth minimum,
// radius 0.25): the edge's crease is scaled by the blend's weight h and fades out where h reaches
// 0 near the ball, past which the box's max is hidden (the blend is the ball's distance alone)
// and the two faces' pieces are one function. The crease goes on over the ball along the
// switch of that max (the plane x = y), as a seam, to the crease's other half.
Expression box_blended_ball() {
  return Expression("b + h*(a-b) - 0.25*h*(1-h)", {}, Box{Vec3::Constant(-1.4), Vec3::Constant(1.4)},
                    {{"a", "max(abs(x), abs(y), abs(z)) - 0.75"},
                     {"b", "hypot(x-0.75, y-0.75, z) - 0.5"},
                     {"h", "clamp(0.5 + 0.5*(b-a)/0.25, 0, 1)"}});
}

TEST(CreaseCurves, ACreaseThatFadesIntoASmoothBlendGoesOnAlongItsSwitchAsASeam) {
  const Expression field = box_blended_ball();
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.curves.size(), 12u);
  EXPECT_EQ(r.corners.size(), 8u);
  EXPECT_EQ(r.stops, 0u);
  std::size_t seams = 0;
  for (const CreaseCurve& c : r.curves) {
    EXPECT_FALSE(c.closed);
    EXPECT_TRUE(c.starts_at_corner && c.ends_at_corner);
    if (c.seam_branch < 0) continue;
    ++seams;
    // From corner to corner of the blended edge, on the surface and on the plane x = y
    // throughout, and over the ball: 0.5 beyond the edge at the ball's top.
    EXPECT_NEAR(std::abs(c.points.front().z() - c.points.back().z()), 1.5, 1e-6);
    double farthest = 0;
    std::size_t one_function = 0;
    for (const Vec3& p : c.points) {
      EXPECT_LE(std::abs(field.value(p)), 1e-9) << p.transpose();
      EXPECT_LE(std::abs(p.x() - p.y()), 1e-9) << p.transpose();
      farthest = std::max(farthest, std::hypot(p.x() - 0.75, p.y() - 0.75));
      const FieldPiece a = field.piece(p, c.pieces[0]), b = field.piece(p, c.pieces[1]);
      one_function += a.value == b.value && a.gradient == b.gradient;
    }
    EXPECT_NEAR(farthest, 0.5, 0.01);
    EXPECT_GT(one_function, 0u);  // the seam part, where the box is hidden
    EXPECT_LT(one_function, c.points.size());  // and the crease at both ends
  }
  EXPECT_EQ(seams, 1u);
}

TEST(CreaseCurves, SeamsThatMeetWhereTheBlendHidesTheirSwitchesEndAtTheCornerThere) {
  // fogleman/sdf's sphere(1) & box(1.5).k(0.1): the box's edges stick out of the ball, so each
  // edge's crease lies in the blend, fading into the ball at both ends. Its seam goes on over
  // the ball to where three faces' switches meet (|x| = |y| = |z| on the ball), and ends there:
  // twelve curves between eight corners, as on a cube. Without the corners the seams ran on
  // along the next edge's switch and stopped there.
  const Expression field("b + (a - b)*h + 0.1*h*(1 - h)", {}, Box{Vec3::Constant(-0.9), Vec3::Constant(0.9)},
                         {{"a", "hypot(x, y, z) - 1"},
                          {"b", "max(abs(x) - 0.75, abs(y) - 0.75, abs(z) - 0.75)"},
                          {"h", "clamp(0.5 - (b - a)*5, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.curves.size(), 12u);
  EXPECT_EQ(r.stops, 0u);
  ASSERT_EQ(r.corners.size(), 8u);
  const double third = 1 / std::sqrt(3.0);
  for (const Vec3& c : r.corners) EXPECT_LE((c.cwiseAbs() - Vec3::Constant(third)).norm(), 1e-8) << c.transpose();
  for (const CreaseCurve& c : r.curves) {
    EXPECT_TRUE(c.starts_at_corner && c.ends_at_corner);
    EXPECT_GE(c.seam_branch, 0);
    for (const Vec3& p : c.points) EXPECT_LE(std::abs(field.value(p)), 1e-9) << p.transpose();
  }
}

TEST(CreaseCurves, ACreaseComesBackFromItsSeamWhicheverWayItRuns) {
  // fogleman/sdf's box(1) | sphere(0.5).translate((0.5, 0, 0.5)).k(0.2): the ball swallows the
  // middle of one of the box's edges and blends its two ends' corners. That edge's crease
  // fades into the blend, runs on over the ball as a seam (the box's switch, x = z) and comes
  // back as a crease beyond: one curve between the two blended corners, which lie where the
  // box's three switches meet (|x| = |y| = |z|). The walk back onto the crease took its
  // direction as +1 whatever the way it went, and stopped there when the crease's tangent
  // pointed the other way.
  const Expression field("b + (a - b)*h - 0.2*h*(1 - h)", {}, Box{Vec3::Constant(-0.8), Vec3::Constant(1.1)},
                         {{"a", "max(abs(x) - 0.5, abs(y) - 0.5, abs(z) - 0.5)"},
                          {"b", "hypot(x - 0.5, y, z - 0.5) - 0.5"},
                          {"h", "clamp(0.5 + (b - a)*2.5, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.curves.size(), 12u);
  EXPECT_EQ(r.corners.size(), 8u);
  EXPECT_EQ(r.stops, 0u);
  const auto blended = [](const Vec3& p) {
    return p.x() > 0.5 && p.z() > 0.5 && std::abs(p.x() - p.z()) < 1e-8 && std::abs(std::abs(p.y()) - p.x()) < 1e-8;
  };
  std::size_t swallowed = 0;
  for (const CreaseCurve& c : r.curves) {
    EXPECT_TRUE(c.starts_at_corner && c.ends_at_corner);
    if (!blended(c.points.front()) || !blended(c.points.back())) continue;
    ++swallowed;
    EXPECT_GE(c.seam_branch, 0);
    EXPECT_NEAR(c.points.front().y(), -c.points.back().y(), 1e-8);
    for (const Vec3& p : c.points) EXPECT_LE(std::abs(p.x() - p.z()), 1e-9) << p.transpose();
  }
  EXPECT_EQ(swallowed, 1u);
}

TEST(CreaseCurves, ASeamThatRunsIntoACreaseEndsAtACornerThatCutsTheCrease) {
  // fogleman/sdf's box(1) - box(0.5).translate((0.5, 0.5, 0)).k(0.1): the cutter's switches
  // between its faces, hidden under the box's faces beyond the blend, run on as seams into
  // the box's edges, at (0.5, 0, +-0.5) and (0, 0.5, +-0.5). Each seam ends at a corner on the
  // edge, and the edge is cut there: three curves end at each such corner (the two halves of
  // the edge and the seam). Without it the seams stopped short of the edges.
  const Expression field("b - (c + b)*h + 0.1*h*(1 - h)", {}, Box{Vec3::Constant(-0.6), Vec3::Constant(0.6)},
                         {{"b", "max(abs(x) - 0.5, abs(y) - 0.5, abs(z) - 0.5)"},
                          {"c", "max(abs(x - 0.5) - 0.25, abs(y - 0.5) - 0.25, abs(z) - 0.25)"},
                          {"h", "clamp(0.5 - (c + b)*5, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  for (const Vec3& t : {Vec3(0.5, 0, 0.5), Vec3(0.5, 0, -0.5), Vec3(0, 0.5, 0.5), Vec3(0, 0.5, -0.5)}) {
    const auto corner = std::find_if(r.corners.begin(), r.corners.end(), [&](const Vec3& c) { return (c - t).norm() < 1e-3; });
    ASSERT_NE(corner, r.corners.end()) << t.transpose();
    std::size_t ending = 0, seams = 0;
    for (const CreaseCurve& c : r.curves) {
      const bool ends = (c.starts_at_corner && (c.points.front() - *corner).norm() < 1e-9) ||
                        (c.ends_at_corner && (c.points.back() - *corner).norm() < 1e-9);
      ending += ends;
      seams += ends && c.seam_branch >= 0;
    }
    EXPECT_EQ(ending, 3u) << t.transpose();
    EXPECT_EQ(seams, 1u) << t.transpose();
  }
}

TEST(CreaseCurves, AHiddenSeamThatEndsAloneAtACornerGoesOnAlongTheSwitchesThatMeetThere) {
  // fogleman/sdf's box(1) - box(0.6).translate((0.45, 0.33, 0.21)).k(0.07): the cutter takes the
  // box's corner off, and the box's edge y = z = 0.5 fades into the pocket's rim and runs on down
  // the pocket's wall x = 0.15 as a seam (the box's switch y = z, hidden behind the blend) to
  // (0.15, 0.15, 0.15), where the box's three switches meet. Only that seam ended there, and the
  // wall's patches broke off at the corner. The box's two other switches leave it along the wall:
  // y = 0.15 down to the pocket's floor (z = -0.09) and z = 0.15 to its side (y = 0.03).
  const Expression field("d0 - (d1 + d0)*h + 0.07*h*(1 - h)", {}, Box{Vec3::Constant(-0.6), Vec3::Constant(0.6)},
                         {{"d0", "max(abs(x) - 0.5, abs(y) - 0.5, abs(z) - 0.5)"},
                          {"d1", "max(abs(x - 0.45) - 0.3, abs(y - 0.33) - 0.3, abs(z - 0.21) - 0.3)"},
                          {"h", "clamp(0.5 - (d1 + d0)*7.142857142857142, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  const Vec3 meet(0.15, 0.15, 0.15);
  std::size_t ending = 0;
  bool down = false, across = false;
  for (const CreaseCurve& c : r.curves) {
    const bool starts = c.starts_at_corner && (c.points.front() - meet).norm() < 1e-6;
    const bool ends = c.ends_at_corner && (c.points.back() - meet).norm() < 1e-6;
    if (!starts && !ends) continue;
    ++ending;
    EXPECT_GE(c.seam_branch, 0);
    const Vec3& far = starts ? c.points.back() : c.points.front();
    down = down || (far - Vec3(0.15, 0.15, -0.09)).norm() < 1e-3;
    across = across || (far - Vec3(0.15, 0.03, 0.15)).norm() < 2e-3;
    for (const Vec3& p : c.points) EXPECT_LE(std::abs(field.value(p)), 1e-9) << p.transpose();
  }
  EXPECT_EQ(ending, 3u);
  EXPECT_TRUE(down);
  EXPECT_TRUE(across);
}

TEST(CreaseCurves, ACornerFoundFromAnotherCornerCutsTheCreaseThroughItInsteadOfTracingItAgain) {
  // fogleman/sdf's box((1.5, 1, 0.5)) | box((0.5, 0.5, 1.2)).translate((0.3, 0.1, 0.4)).k(0.08):
  // the tower's bottom lies 0.05 above the slab's, within the blend, which bulges the slab's
  // bottom into a flat bump. The seams from the bump's corners (walked from those corners in the
  // pass over them) run into the slab's bottom edges, at corners that pass found. The edges ran
  // through those corners uncut, and each was traced twice more from them, taken for creases
  // leaving them; the patch boundary at the slab's corner was then ambiguous.
  const Expression field("d1 + (d0 - d1)*h - 0.08*h*(1 - h)", {}, Box{Vec3(-0.996, -0.746, -0.496), Vec3(0.996, 0.746, 1.246)},
                         {{"d0", "max(abs(x) - 0.75, abs(y) - 0.5, abs(z) - 0.25)"},
                          {"d1", "max(abs(x - 0.3) - 0.25, abs(y - 0.1) - 0.25, abs(z - 0.4) - 0.6)"},
                          {"h", "clamp(0.5 + (d1 - d0)*6.25, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  // The slab's four bottom edges, each traced once: their curves' lengths sum to theirs.
  for (const double y : {-0.5, 0.5}) {
    double length = 0;
    for (const CreaseCurve& c : r.curves) {
      const bool on_edge = std::all_of(c.points.begin(), c.points.end(), [&](const Vec3& p) {
        return std::abs(p.y() - y) < 1e-9 && std::abs(p.z() + 0.25) < 1e-9;
      });
      if (!on_edge) continue;
      for (std::size_t i = 0; i + 1 < c.points.size(); ++i) length += (c.points[i + 1] - c.points[i]).norm();
    }
    EXPECT_NEAR(length, 1.5, 1e-6) << y;
  }
}

TEST(CreaseCurves, AHiddenSeamThatTurnsAlongAnotherSwitchEndsAtACornerThere) {
  // fogleman/sdf's box(1) & box(0.82).translate((-0.08, 0.31, -0.6)).k(0.09): the small box's
  // switches run hidden over the big box's bottom face (z = -0.5), which the blend takes there,
  // 0.1 above the small box's centre: a square |x + 0.08| = 0.1, |y - 0.31| = 0.1 where the small
  // box's z face is its largest, with rays from its corners. A seam along a side of the square
  // cannot step past the next corner, where its switch turns along the other side's (beyond,
  // the choice it separates is hidden), and no step crossed that switch: the walks stopped there,
  // one step short or right on it, and the layout refused the stops.
  const Expression field("d1 + (d0 - d1)*h + 0.09*h*(1 - h)", {}, Box{Vec3(-0.572, -0.182, -0.582), Vec3(0.412, 0.582, -0.108)},
                         {{"d0", "max(abs(x) - 0.5, abs(y) - 0.5, abs(z) - 0.5)"},
                          {"d1", "max(abs(x + 0.08) - 0.41, abs(y - 0.31) - 0.41, abs(z + 0.6) - 0.41)"},
                          {"h", "clamp(0.5 - (d1 - d0)*5.555555555555555, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  for (const Vec3& t : {Vec3(-0.18, 0.21, -0.5), Vec3(0.02, 0.21, -0.5), Vec3(-0.18, 0.41, -0.5), Vec3(0.02, 0.41, -0.5)}) {
    EXPECT_TRUE(has_corner(r, t)) << t.transpose();
  }
  for (const CreaseCurve& c : r.curves) EXPECT_TRUE(c.closed || (c.starts_at_corner && c.ends_at_corner));
}

TEST(CreaseCurves, ACurveCutWhereAHiddenSeamEndsTakesTheHiddenChoicesAsTheFieldDoesOnEachPart) {
  // fogleman/sdf's box(1) | box(0.88).translate((0.54, -0.53, -0.5)).k(0.13): the big box's edge
  // x = 0.5, z = -0.5 runs on as a hidden seam over the small box's face y = -0.09, to a corner on
  // that face's bottom edge. The edge is cut there, and its short part beyond the seam kept the code
  // it was traced with, which takes the big box's z face where the field takes its x face
  // (AdaptiveCreases.ABoxEdgeCutWhereAHiddenSeamEndsOnIt...). Every curve's codes take each choice
  // hidden at its middle (flipping it changes nothing there) as the field takes it there.
  const Expression field("d1 + (d0 - d1)*h - 0.13*h*(1 - h)", {}, Box{Vec3(-0.804, -1.274, -1.244), Vec3(1.284, 0.804, 0.804)},
                         {{"d0", "max(abs(x) - 0.5, abs(y) - 0.5, abs(z) - 0.5)"},
                          {"d1", "max(abs(x - 0.54) - 0.44, abs(y + 0.53) - 0.44, abs(z + 0.5) - 0.44)"},
                          {"h", "clamp(0.5 + (d1 - d0)*3.846153846153846, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  EXPECT_TRUE(has_corner(r, Vec3(0.94, -0.09, -0.94)));
  std::size_t checked = 0;
  for (const CreaseCurve& c : r.curves) {
    const std::size_t n = c.points.size();
    const Vec3 middle = n % 2 ? c.points[n / 2] : Vec3(0.5 * (c.points[n / 2 - 1] + c.points[n / 2]));
    Field::BranchRecord record;
    ASSERT_TRUE(field.branch_record(middle, record));
    for (const auto& code : c.pieces)
      for (std::size_t k = 0; k < code.size(); ++k) {
        if (code[k] == Field::kFreeBranch || static_cast<int>(k) == c.seam_branch || code[k] == record.taken[k]) continue;
        auto taken = code;
        taken[k] = record.taken[k];
        const auto [v0, g0] = field.piece_first_order(middle, code);
        const auto [v1, g1] = field.piece_first_order(middle, taken);
        EXPECT_FALSE(same_to_rounding(v0, g0, v1, g1)) << "choice " << k << " hidden at " << middle.transpose();
        ++checked;
      }
  }
  EXPECT_GT(checked, 0u);  // the crease's own choices, which differ from the field's on one side
}

TEST(CreaseCurves, ACreaseTracedTwiceBetweenTheSameCornersIsKeptOnce) {
  // fogleman/sdf's box(1) | box(0.48).translate((0.16, 0.44, 0.03)).k(0.12): the big box's edge
  // x = y = 0.5 runs up from its corner into the blend, where a corner cuts it at z = -0.311. It
  // was traced from the box's corner and again as part of a walk cut at the blend's corner: two
  // curves on the same edge between the same corners, whose darts met at the box's corner along
  // the same direction, and the layout refused them. No two curves between the same corners now
  // lie on each other.
  const Expression field("d1 + (d0 - d1)*h - 0.12*h*(1 - h)", {}, Box{Vec3(-0.762, -0.762, -0.762), Vec3(0.762, 0.942, 0.762)},
                         {{"d0", "max(abs(x) - 0.5, abs(y) - 0.5, abs(z) - 0.5)"},
                          {"d1", "max(abs(x - 0.16) - 0.24, abs(y - 0.44) - 0.24, abs(z - 0.03) - 0.24)"},
                          {"h", "clamp(0.5 + (d1 - d0)*4.166666666666667, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  EXPECT_GE(r.duplicates, 1u);
  const auto near = [](const Vec3& a, const Vec3& b) { return (a - b).norm() <= 1e-3; };
  for (std::size_t i = 0; i < r.curves.size(); ++i)
    for (std::size_t j = i + 1; j < r.curves.size(); ++j) {
      const CreaseCurve &a = r.curves[i], &b = r.curves[j];
      if (a.closed || b.closed) continue;
      const bool same_ends = (near(a.points.front(), b.points.front()) && near(a.points.back(), b.points.back())) ||
                             (near(a.points.front(), b.points.back()) && near(a.points.back(), b.points.front()));
      if (!same_ends) continue;
      const Vec3& mid = a.points[a.points.size() / 2];
      double d = std::numeric_limits<double>::infinity();
      for (std::size_t k = 0; k + 1 < b.points.size(); ++k) {
        const Vec3 e = b.points[k + 1] - b.points[k];
        const double t = std::clamp((mid - b.points[k]).dot(e) / e.squaredNorm(), 0.0, 1.0);
        d = std::min(d, (b.points[k] + t * e - mid).norm());
      }
      EXPECT_GT(d, 1e-3) << "curves " << i << " and " << j << " from " << a.points.front().transpose();
    }
}

TEST(CreaseProjection, ProjectToSeamLandsOnTheSwitchWhereThePiecesAreOneFunction) {
  const Expression field = box_blended_ball();
  const CreaseTracingResult r = trace_creases(field);
  const auto seam = std::find_if(r.curves.begin(), r.curves.end(), [](const CreaseCurve& c) { return c.seam_branch >= 0; });
  ASSERT_NE(seam, r.curves.end());
  const auto k = static_cast<std::size_t>(seam->seam_branch);
  // Over the ball, off the surface and off the plane x = y.
  const CreaseProjection c = project_to_seam(field, Vec3(1.2, 1.05, 0.1), seam->pieces[0], k);
  ASSERT_TRUE(c.ok()) << to_string(c.status);
  EXPECT_LE(std::abs(field.value(c.point)), 1e-9);
  EXPECT_LE(std::abs(c.point.x() - c.point.y()), 1e-9);
  EXPECT_NEAR((c.point - Vec3(0.75, 0.75, 0)).norm(), 0.5, 1e-9);  // the blend is the ball's alone there
  // There project_to_crease has two equal gradients.
  const std::vector<std::vector<std::uint8_t>> two{seam->pieces[0], seam->pieces[1]};
  EXPECT_EQ(project_to_crease(field, Vec3(1.2, 1.05, 0.1), two).status, CreaseStatus::DependentGradients);
  // The switch of a branch point the model does not have: nothing to land on.
  EXPECT_EQ(project_to_seam(field, Vec3(1.2, 1.05, 0.1), seam->pieces[0], 1000).status, CreaseStatus::NotFinite);
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

TEST(CreaseCurves, PiecesThatDifferOnlyInRoundingStartNoCrease) {
  // fogleman/sdf's model with its holes cut by a smooth difference (cdp.sdf: (sphere(1) &
  // box(1.5)).difference(three cylinders, k=0.1)). On the holes' walls the blend is d0 - (d1 + d0)
  // h with h = 1: the two sides of d0's max differ there in their last bits only, and the
  // tracer started 227 curves of 1 to 21 points from them (402 stops). The creases are the six
  // circles where the ball meets the box's faces and the twelve edges where the tunnels cross,
  // between eight corners.
  const Expression field("d0 - (d1 + d0)*h + 0.1*h*(1 - h)", {}, Box{Vec3::Constant(-0.9), Vec3::Constant(0.9)},
                         {{"d0", "max(hypot(x, y, z) - 1, max(abs(x) - 0.75, abs(y) - 0.75, abs(z) - 0.75))"},
                          {"d1", "min(hypot(z, y) - 0.5, hypot(x, z) - 0.5, hypot(x, y) - 0.5)"},
                          {"h", "clamp(0.5 - (d1 + d0)*5, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  EXPECT_EQ(r.stops, 0u);
  EXPECT_EQ(r.corners.size(), 8u);
  std::size_t loops = 0, edges = 0;
  for (const CreaseCurve& c : r.curves) {
    if (c.closed) {
      ++loops;
      for (const Vec3& p : c.points) EXPECT_NEAR(p.norm(), 1, 1e-8);
    } else {
      ++edges;
      EXPECT_TRUE(c.starts_at_corner && c.ends_at_corner);
    }
  }
  EXPECT_EQ(loops, 6u);
  EXPECT_EQ(edges, 12u);
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

TEST(FieldPieces, AChoiceHiddenBehindABlendIsFreeThoughItChangesTheLastBits) {
  // A box with two crossing holes cut by a smooth difference (cdp.sdf: box(1.5).difference(
  // cylinder(0.5).orient(X) | cylinder(0.5).orient(Y), k=0.1)). In the tunnels the blend is
  // d0 - (d1 + d0) h at h = 1: the box's max changes the field in its last bits only. Compared
  // bit for bit it was fixed in one tunnel's pieces at some points and free at others, two
  // codes for one wall. The four arcs where the tunnels meet carry one code per tunnel.
  const Expression field("d0 - (d1 + d0)*h + 0.1*h*(1 - h)", {}, Box{Vec3::Constant(-0.9), Vec3::Constant(0.9)},
                         {{"d0", "max(abs(x) - 0.75, abs(y) - 0.75, abs(z) - 0.75)"},
                          {"d1", "min(hypot(z, y) - 0.5, hypot(x, z) - 0.5)"},
                          {"h", "clamp(0.5 - (d1 + d0)*5, 0, 1)"}});
  const CreaseTracingResult r = trace_creases(field);
  // Codes as strings: a set of byte vectors woke GCC 12's false -Wstringop-overread in a unity batch.
  std::set<std::string> tunnels;
  std::size_t arcs = 0;
  for (const CreaseCurve& c : r.curves) {
    if (c.points.front().head<2>().norm() > 1e-3) continue;  // a box's edge, not from (0, 0, +-0.5)
    ++arcs;
    for (const auto& code : {c.pieces[0], c.pieces[1]}) tunnels.insert(std::string(code.begin(), code.end()));
  }
  EXPECT_EQ(arcs, 4u);
  EXPECT_EQ(tunnels.size(), 2u);
}

}  // namespace
}  // namespace cdp
