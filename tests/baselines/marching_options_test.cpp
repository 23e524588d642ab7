// Checks <cdp/baselines/marching_options.h>: the paper's precision convention, the cell size
// resolution and its errors, and the lattice both traversals share.
#include <cdp/baselines/marching_options.h>

#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>

#include <gtest/gtest.h>

namespace cdp {
namespace {

// A sphere that claims constraint points 0.05 apart, standing in for a variational model.
class SphereWithConstraints : public Field {
 public:
  SphereWithConstraints() { set_bounds(sphere_.bounds()); }
  std::string type_name() const override { return "sphere_with_constraints"; }
  std::optional<double> constraint_spacing() const override { return 0.05; }

 protected:
  double eval_value(const Vec3& p) const override { return sphere_.value(p); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override { return sphere_.value_gradient(p, g); }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override {
    return sphere_.gradient_hessian(p, g, h);
  }

 private:
  Sphere sphere_{Vec3::Zero(), 1.0};
};

TEST(MarchingOptions, PrecisionScalesFollowThePaper) {
  const double expected[6] = {1.0, 0.7, 0.6, 0.5, 0.4, 0.3};
  for (int p = 0; p <= 5; ++p) EXPECT_DOUBLE_EQ(precision_scale(p), expected[p]);
  EXPECT_THROW(precision_scale(6), InvalidInputError);
  EXPECT_THROW(precision_scale(-1), InvalidInputError);
}

TEST(MarchingOptions, CellSizeFromPrecisionUsesTheConstraintSpacing) {
  const SphereWithConstraints field;
  MarchingOptions o;
  o.precision = 1;
  EXPECT_DOUBLE_EQ(resolve_cell_size(field, o), 0.05 * 0.7);
  o.cell_size = 0.1;
  EXPECT_THROW(resolve_cell_size(field, o), InvalidInputError);  // both given
}

TEST(MarchingOptions, CellSizeErrors) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  MarchingOptions o;
  EXPECT_DOUBLE_EQ(resolve_cell_size(sphere, o), 2.2 / 64);  // default: 1/64 of the box side
  o.cell_size = -0.1;
  EXPECT_THROW(resolve_cell_size(sphere, o), InvalidInputError);
  o.cell_size = std::nan("");
  EXPECT_THROW(resolve_cell_size(sphere, o), InvalidInputError);
  o.cell_size = 0;
  o.precision = 3;
  EXPECT_THROW(resolve_cell_size(sphere, o), InvalidInputError);
}

TEST(MarchingOptions, LatticeIsAnchoredAtTheBoxMinimumAndCoversIt) {
  const Torus torus(Vec3(1, 2, 3), 1.0, 0.4);
  const MarchingLattice l = make_marching_lattice(torus, 0.3);
  EXPECT_EQ(l.origin, torus.bounds().min);
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(l.origin[a] + l.h * l.cells[a], torus.bounds().max[a] - 1e-9);
    EXPECT_LT(l.origin[a] + l.h * (l.cells[a] - 1), torus.bounds().max[a]);
  }
  EXPECT_THROW(make_marching_lattice(torus, 1e-7), InvalidInputError);
}

}  // namespace
}  // namespace cdp
