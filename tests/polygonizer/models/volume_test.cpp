// The sampled-volume model (polygonizer/include/cdp/core/models/volume.h): it interpolates its
// samples, its derivatives are the interpolant's (central differences), its bounds hold, bad
// grids are refused by name, and sampled distance fields mesh within the interpolation error of
// the surfaces they sample, with their topology.
#include <gtest/gtest.h>

#include <cdp/baselines/marching_cubes.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/errors.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/models/expression.h>
#include <cdp/core/models/level_shift.h>
#include <cdp/core/models/volume.h>

#include "src/adaptive/failure_message.h"

#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace cdp {
namespace {

// n samples per axis of f over the cube [-half, half]^3 (spacing 2 half / (n - 1)).
VolumeSamples sample_cube(const std::function<double(const Vec3&)>& f, std::size_t n, double half) {
  VolumeSamples s;
  s.dims = {n, n, n};
  s.origin = Vec3::Constant(-half);
  s.spacing = Vec3::Constant(2 * half / static_cast<double>(n - 1));
  s.values.reserve(n * n * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t k = 0; k < n; ++k)
        s.values.push_back(f(s.origin + Vec3(double(i), double(j), double(k)).cwiseProduct(s.spacing)));
  return s;
}

double sphere_distance(const Vec3& p) { return p.norm() - 1.0; }
double torus_distance(const Vec3& p) { return Eigen::Vector2d(std::hypot(p.x(), p.y()) - 1.0, p.z()).norm() - 0.4; }

TEST(Volume, InterpolatesItsSamplesAndReadsInsideEitherWay) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  VolumeSamples s;
  s.dims = {7, 8, 9};
  s.origin = Vec3(1, -2, 0.5);
  s.spacing = Vec3(0.5, 0.25, 1.0);
  // Outside everywhere (> level 0.5) but for two samples in the middle. The spline's coefficients
  // ring around jumps (by up to 3 times a jump between neighbours), so the outside is smooth.
  for (std::size_t f = 0; f < 7 * 8 * 9; ++f) s.values.push_back(2.0 + 0.05 * u(rng));
  for (std::size_t f : {(3 * 8 + 3) * 9 + 4, (3 * 8 + 4) * 9 + 4}) s.values[f] = u(rng) * 0.2;  // two inside
  // The same samples upside down for a density, whose inside is above the level.
  VolumeSamples flipped = s;
  for (double& v : flipped.values) v = 1.0 - v;
  const Volume below(s, 0.5, VolumeInside::Below), above(flipped, 0.5, VolumeInside::Above);
  EXPECT_EQ(below.bounds().min, s.origin);
  EXPECT_TRUE(below.bounds().max.isApprox(Vec3(4, -0.25, 8.5)));
  for (std::size_t i = 0; i < 7; ++i)
    for (std::size_t j = 0; j < 8; ++j)
      for (std::size_t k = 0; k < 9; ++k) {
        const Vec3 p = s.origin + Vec3(double(i), double(j), double(k)).cwiseProduct(s.spacing);
        const double sample = s.values[(i * 8 + j) * 9 + k];
        EXPECT_NEAR(below.value(p), sample - 0.5, 1e-12) << i << " " << j << " " << k;
        EXPECT_NEAR(above.value(p), 0.5 - (1.0 - sample), 1e-12);
      }
}

TEST(Volume, DerivativesAreTheInterpolantsAndItsBoundsHold) {
  const Volume field(sample_cube(torus_distance, 16, 2.0), 0.0);
  const Box box = field.bounds();
  std::mt19937 rng(5);
  // Beyond the grid too, where F is its value at the nearest point of the box plus the distance.
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  const double h = 1e-6;
  double steepest = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 p = box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size());
    Vec3 g, g2;
    Mat3 H;
    const double v = field.value(p);
    ASSERT_EQ(v, field.value_gradient(p, g));
    ASSERT_EQ(v, field.gradient_hessian(p, g2, H));
    ASSERT_EQ(g, g2);
    steepest = std::max(steepest, g.norm());
    for (int a = 0; a < 3; ++a) {
      Vec3 e = Vec3::Zero();
      e[a] = h;
      EXPECT_NEAR((field.value(p + e) - field.value(p - e)) / (2 * h), g[a], 1e-7 * std::max(1.0, g.norm()));
      const Vec3 dg = (field.gradient(p + e) - field.gradient(p - e)) / (2 * h);
      for (int b = 0; b < 3; ++b) EXPECT_NEAR(dg[b], H(b, a), 1e-5 * std::max(1.0, H.norm())) << p.transpose();
    }
    EXPECT_EQ(H, H.transpose());
  }
  ASSERT_TRUE(field.lipschitz_bound());
  EXPECT_GE(*field.lipschitz_bound(), steepest);
  // Far beyond the grid: outside, by at least the distance to the box (no mirrored copies of the
  // torus every 2 (n - 1) samples), and a point that is not finite gives NaN, not a read.
  for (const Vec3& far : {Vec3(12.5, 0, 0), Vec3(0, -40, 3), Vec3(1e300, 0, 0), Vec3(-1e19, 1e19, 0)}) {
    const double beyond = (far - far.cwiseMax(box.min).cwiseMin(box.max)).norm();
    EXPECT_GE(field.value(far), beyond) << far.transpose();  // equal once the distance swamps F's value
    EXPECT_GT(field.value(far), 0) << far.transpose();
  }
  EXPECT_TRUE(std::isnan(field.value(Vec3(std::nan(""), 0, 0))));
  // value_range holds on sub-boxes, checked at points inside each.
  std::uniform_real_distribution<double> w(0, 1);
  for (int trial = 0; trial < 30; ++trial) {
    const Vec3 lo = box.min + Vec3(w(rng), w(rng), w(rng)).cwiseProduct(box.size()) * 0.8;
    const Box region{lo, lo + box.size() * 0.2 * w(rng) + Vec3::Constant(1e-3)};
    const auto range = field.value_range(region);
    ASSERT_TRUE(range);
    for (int k = 0; k < 50; ++k) {
      const double v = field.value(region.min + Vec3(w(rng), w(rng), w(rng)).cwiseProduct(region.size()));
      EXPECT_GE(v, range->first - 1e-12);
      EXPECT_LE(v, range->second + 1e-12);
    }
  }
}

// gradient_range bounds the derivatives inside sub-boxes, checked at points inside each; near
// the grid's faces (mirrored coefficients) and beyond the grid it gives nothing. values_on_lattice
// gives values()'s numbers bit for bit, separably inside the grid, point by point across its box.
TEST(Volume, GradientRangesHoldAndLatticesAreTheirPointsValues) {
  const VolumeSamples samples = sample_cube(torus_distance, 16, 2.0);
  VolumeSamples density = samples;  // the same surface read the other way: inside above the level
  for (double& v : density.values) v = -v;
  const Volume below(samples, 0.0), above(density, 0.0, VolumeInside::Above);
  const Box box = below.bounds();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> w(0, 1);
  int checked = 0;
  for (const Volume* field : {&below, &above})
    for (int trial = 0; trial < 40; ++trial) {
      const Vec3 lo = box.min + Vec3(w(rng), w(rng), w(rng)).cwiseProduct(box.size()) * 0.8;
      const Box region{lo, lo + box.size() * 0.2 * w(rng) + Vec3::Constant(1e-3)};
      const auto range = field->gradient_range(region);
      if (!range) continue;
      ++checked;
      for (int k = 0; k < 50; ++k) {
        const Vec3 g = field->gradient(region.min + Vec3(w(rng), w(rng), w(rng)).cwiseProduct(region.size()));
        EXPECT_TRUE((g.array() >= range->first.array() - 1e-12).all()) << g.transpose() << " / " << range->first;
        EXPECT_TRUE((g.array() <= range->second.array() + 1e-12).all()) << g.transpose() << " / " << range->second;
      }
    }
  EXPECT_GT(checked, 20);
  EXPECT_FALSE(below.gradient_range(Box{box.min, box.min + Vec3::Constant(0.1)}));  // the outermost layers
  EXPECT_FALSE(below.gradient_range(Box{box.min - Vec3::Constant(0.5), box.center()}));  // beyond the grid
  // Near the torus's outer equator the gradient points along +x: that component's interval is
  // positive, so the box holds no critical point.
  const auto outer = below.gradient_range(Box{Vec3(1.35, -0.05, -0.05), Vec3(1.45, 0.05, 0.05)});
  ASSERT_TRUE(outer);
  EXPECT_GT(outer->first.x(), 0);

  const LevelShift shifted(below, 0.25);
  const auto same = [](const Field& field, const Vec3& origin, double step, int n) {
    std::vector<double> lattice(static_cast<std::size_t>(n) * n * n), points(lattice.size());
    const std::size_t before = field.counts().value;
    field.values_on_lattice(origin, step, n, lattice.data());
    EXPECT_EQ(field.counts().value - before, lattice.size());
    for (int c = 0; c < n; ++c)
      for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
          const std::size_t i = (static_cast<std::size_t>(c) * n + b) * n + a;
          points[i] = field.value(origin + step * Vec3(a, b, c));
          if (lattice[i] != points[i]) return ::testing::AssertionFailure() << a << " " << b << " " << c;
        }
    return ::testing::AssertionSuccess();
  };
  for (const Field* field : {static_cast<const Field*>(&below), static_cast<const Field*>(&above),
                             static_cast<const Field*>(&shifted)}) {
    EXPECT_TRUE(same(*field, Vec3(-1.3, 0.2, -0.71), 0.0137, 11));
    EXPECT_TRUE(same(*field, box.min, 4.0 / 7, 8));                     // the whole box, its faces included
    EXPECT_TRUE(same(*field, Vec3(1.8, 1.7, -2.1), 0.05, 9));            // across the box: point by point
    EXPECT_TRUE(same(*field, Vec3(0.3, 0.3, 0.3), 0.1, 1));
  }
}

TEST(Volume, RefusesGridsItCannotInterpolateByName) {
  const auto expect_error = [](VolumeSamples s, double level, const std::string& words) {
    try {
      Volume v(std::move(s), level);
      ADD_FAILURE() << "no error for " << words;
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  const VolumeSamples good = sample_cube(sphere_distance, 6, 1.5);
  VolumeSamples s = good;
  s.dims = {6, 6, 3};
  s.values.resize(108);
  expect_error(s, 0, "at least 4 samples along each axis, found 3 along z");
  s = good;
  s.values.pop_back();
  expect_error(s, 0, "215 values for a grid of 216 samples");
  s = good;
  s.spacing.y() = 0;
  expect_error(s, 0, "spacing along y must be positive");
  s = good;
  s.values[(2 * 6 + 3) * 6 + 2] = std::nan("");
  expect_error(s, 0, "sample [2, 3, 2] is not finite");
  expect_error(good, 2.0, "reaches the level on the grid's faces near sample [0, 0, ");
  expect_error(good, std::nan(""), "level must be finite");
  // Outside samples on every face, but a deep inside next to one: the spline dips below the level
  // between them on the face (samples alone would pass it).
  s = good;
  for (double& v : s.values) v = 100;
  for (std::size_t j = 2; j < 4; ++j)
    for (std::size_t k = 2; k < 4; ++k) {
      s.values[(0 * 6 + j) * 6 + k] = 0.01;
      for (std::size_t i = 1; i < 5; ++i) s.values[(i * 6 + j) * 6 + k] = -100;
    }
  expect_error(s, 0, "reaches the level on the grid's faces near sample [");
}

struct Sampled {
  const char* name;
  double (*distance)(const Vec3&);
  double half;
  int genus;
};

// A distance field sampled at three resolutions meshes closed with its genus, and every vertex
// lies within the interpolation error of the sampled surface: that error is measured apart, as
// the largest |S - d| at points spread through a band around the surface (|grad d| = 1, so a
// vertex where S = 0 is |S - d| from it).
TEST(Volume, SampledDistanceFieldsMeshWithinTheirInterpolationErrorWithTheirTopology) {
  for (const Sampled& c : {Sampled{"sphere", sphere_distance, 1.5, 0}, Sampled{"torus", torus_distance, 1.6, 1}}) {
    double previous = std::numeric_limits<double>::infinity();
    for (std::size_t n : {24, 40, 64}) {
      const Volume field(sample_cube(c.distance, n, c.half), 0.0);
      std::mt19937 rng(11);
      std::uniform_real_distribution<double> u(-c.half, c.half);
      const double band = 2 * field.spacing().x();
      double interpolation = 0;
      for (int k = 0; k < 200000; ++k) {
        const Vec3 p(u(rng), u(rng), u(rng));
        if (std::abs(c.distance(p)) < band) interpolation = std::max(interpolation, std::abs(field.value(p) - c.distance(p)));
      }
      const PolygonizeResult r = polygonize_adaptive(field, AdaptiveOptions{});
      const MeshTopology t = analyze_topology(r.mesh);
      EXPECT_TRUE(t.watertight()) << c.name << " " << n;
      EXPECT_EQ(t.components, 1u) << c.name << " " << n;
      EXPECT_EQ(t.genus, c.genus) << c.name << " " << n;
      double worst = 0;
      for (const Vec3& v : r.mesh.positions) worst = std::max(worst, std::abs(c.distance(v)));
      // 1.5: the band's sampling of |S - d| misses its peaks by a little; 1e-9: Newton's tolerance.
      EXPECT_LE(worst, 1.5 * interpolation + 1e-9) << c.name << " " << n << " interpolation error " << interpolation;
      EXPECT_LT(interpolation, previous) << c.name << " " << n;  // finer samples, closer surface
      previous = interpolation;
    }
  }
}

// LevelShift: F - c passes every hook on, so a sphere's distance at level 0.5 is the sphere of
// radius 1.5, and the derivatives are F's.
TEST(LevelShift, ShiftsTheValueAndNothingElse) {
  const Volume field(sample_cube(sphere_distance, 32, 2.0), 0.0);
  const LevelShift shifted(field, 0.5);
  const Vec3 p(0.3, -0.7, 1.1);
  Vec3 g, gs;
  Mat3 h, hs;
  EXPECT_EQ(shifted.gradient_hessian(p, gs, hs), field.gradient_hessian(p, g, h) - 0.5);
  EXPECT_EQ(g, gs);
  EXPECT_EQ(h, hs);
  EXPECT_EQ(shifted.bounds().min, field.bounds().min);
  const auto range = field.value_range(shifted.bounds()), shifted_range = shifted.value_range(shifted.bounds());
  EXPECT_EQ(shifted_range->first, range->first - 0.5);
  const PolygonizeResult r = polygonize_adaptive(shifted, AdaptiveOptions{});
  for (const Vec3& v : r.mesh.positions) EXPECT_NEAR(v.norm(), 1.5, 1e-3);
  EXPECT_THROW(LevelShift(field, std::nan("")), InvalidInputError);
}

// A sampled volume's bend far tighter than a sample (kBelowSamples of the spacing) and than
// min_edge is the noise of its samples, which no run made again meshes (the raw brain scan:
// 10 s to its first failure, 30 s to its last recovery's); a bend as tight in a model that is not
// sampled, or one within either bound, is not.
TEST(Volume, ABendFarBelowASampleIsItsNoise) {
  const Volume field(sample_cube(sphere_distance, 24, 1.5), 0.0);  // spacing 0.13
  const adaptive::Settings s = adaptive::resolve_settings(field, AdaptiveOptions{});
  const double spacing = field.spacing().x();
  ASSERT_EQ(field.sample_spacing(), spacing);
  ASSERT_LT(s.sizing.min_edge, adaptive::kBelowSamples * spacing);  // 0.0104 against 0.013
  const Vec3 p = Vec3::UnitX();
  EXPECT_TRUE(adaptive::noise_in_volume(field, s, {0.5 * s.sizing.min_edge, p}));
  // Under a tenth of a sample but over min_edge: the run's own edges may still mend it.
  EXPECT_FALSE(adaptive::noise_in_volume(field, s, {0.5 * (s.sizing.min_edge + adaptive::kBelowSamples * spacing), p}));
  EXPECT_FALSE(adaptive::noise_in_volume(field, s, {1.0, p}));
  // F - level is still the volume's samples; an expression has none.
  EXPECT_TRUE(adaptive::noise_in_volume(LevelShift(field, 0.1), s, {0.5 * s.sizing.min_edge, p}));
  const Expression sphere("sqrt(x^2+y^2+z^2)-1", {}, field.bounds());
  EXPECT_FALSE(sphere.sample_spacing().has_value());
  EXPECT_FALSE(adaptive::noise_in_volume(sphere, s, {0.5 * s.sizing.min_edge, p}));
  // Its error names the noise first, and the smoothing that removes it, not a shorter min_edge.
  const std::string noise =
      adaptive::explain_failure(field, AdaptiveOptions{}, s, "STOPPED", {0.5 * s.sizing.min_edge, p}, "");
  EXPECT_EQ(noise.find("adaptive: the surface bends"), 0u) << noise;
  EXPECT_NE(noise.find("noise of its samples"), std::string::npos) << noise;
  EXPECT_NE(noise.find("smoothing the samples"), std::string::npos) << noise;
  EXPECT_NE(noise.find("Where the run stopped: STOPPED"), std::string::npos) << noise;
  const std::string bend =
      adaptive::explain_failure(sphere, AdaptiveOptions{}, s, "STOPPED", {0.5 * s.sizing.min_edge, p}, "");
  EXPECT_EQ(bend.find("STOPPED; the surface bends"), 0u) << bend;
  EXPECT_EQ(bend.find("noise"), std::string::npos) << bend;
}

// Not every bend that tight is noise: two Gaussian blobs sampled on 24^3 points, at a level 1e-5
// below the value of their saddle, are joined by a neck 0.006 wide (4 % of a sample, under the
// default min_edge, 0.014). The first attempt's mesh closes over it, and the second blob, seeded
// after, runs into that mesh: the attempt is made again with it seeded first (seeds_first), and
// its fronts, grown from there, cross the neck: one component, as before the noise rule. (Before
// that attempt, the run made again with min_edge lowered under the neck's width meshed it.)
TEST(Volume, ANeckAHairFromASaddleIsNotTakenForNoise) {
  const auto blobs = [](const Vec3& p) {
    return std::exp(-(p - Vec3(0.8, 0, 0)).squaredNorm() / 0.5) + std::exp(-(p + Vec3(0.8, 0, 0)).squaredNorm() / 0.5);
  };
  const VolumeSamples samples = sample_cube(blobs, 24, 2.0);
  const double saddle = 0.5 - Volume(samples, 0.5, VolumeInside::Above).value(Vec3::Zero());  // F = level - S
  const Volume field(samples, saddle - 1e-5, VolumeInside::Above);
  const PolygonizeResult r = polygonize_adaptive(field, AdaptiveOptions{});
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 0);
  EXPECT_GE(r.stats.adaptive->seeding.seeds_first, 1u);
}

// A small component beside the surface, inside the band of seed-grid cells the surface crosses or
// borders, where neither a grid edge nor the small-component search looks: a sphere's distance
// on 32^3 samples with one sample 0.27 outside it set to -0.02 (the spline interpolates, so F is
// -0.02 there, and a bubble about 0.06 across surrounds it). Without the band scan the run meshed
// the sphere alone, exit 0, in 6 of 8 such cases; marching cubes on a full grid of 0.02 finds two
// components.
TEST(Volume, ASmallComponentBesideTheSurfaceIsMeshed) {
  VolumeSamples samples = sample_cube(sphere_distance, 32, 2.0);
  const std::size_t node = (22 * 32 + 22) * 32 + 19;
  const Vec3 at = samples.origin + Vec3(22, 22, 19).cwiseProduct(samples.spacing);
  ASSERT_NEAR(samples.values[node], 0.269, 1e-3);
  samples.values[node] = -0.02;
  const Volume field(samples, 0.0);
  MarchingOptions mo;
  mo.cell_size = 0.02;
  mo.traversal = Traversal::Grid;
  const MeshTopology reference = analyze_topology(marching_cubes(field, mo).mesh);
  ASSERT_EQ(reference.components, 2u);

  const PolygonizeResult r = polygonize_adaptive(field, AdaptiveOptions{});
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, reference.components);
  EXPECT_EQ(t.genus, 0);
  EXPECT_GT(r.stats.adaptive->seeding.band_components, 0u);
  // The second component is the bubble: vertices within a sample of the node.
  std::size_t near_node = 0;
  for (const Vec3& v : r.mesh.positions) near_node += (v - at).norm() < 0.1;
  EXPECT_GE(near_node, 4u);
  // A clean sampled sphere proves every cell of its band free of critical points: nothing scanned.
  const Volume clean(sample_cube(sphere_distance, 32, 2.0), 0.0);
  EXPECT_EQ(polygonize_adaptive(clean, AdaptiveOptions{}).stats.adaptive->seeding.band_cells, 0u);
}

}  // namespace
}  // namespace cdp
