#include "blocks.h"

#include "block_task.h"
#include "edge_length.h"
#include "lockstep.h"
#include "missed_necks.h"
#include "../parallel.h"
#include "../union_find.h"

#include <cdp/core/curvature.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/triangle_intersection.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <queue>
#include <random>
#include <tuple>
#include <stdexcept>
#include <string>
#include <utility>

namespace cdp::adaptive {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Triangles a block is cut for, as the seed grid estimates the surface (1.05-2.2 times below the
// count): enough that a block's fronts outweigh its seams (a seam vertex costs a traced curve's
// Hessians and two blocks' bridges; a block of 2500 triangles has about a hundred), and few
// enough that the bunny VIS-800 at factor 3 (1.4 * 10^4 triangles) gets four blocks and tanglecube
// at factor 12 sixty-four, so that two threads share them evenly. With 10^4 the torus at factor
// 40 took 1.73 s on two threads in 25 blocks against 1.05 s in 128 at 2500, one thread 2.67 s
// against 2.00 s (one run each).
constexpr double kTrianglesPerBlock = 2500;
// A field whose calls cost more than their points (Field::costly_calls) is cut for
// kLockstepTasks blocks in flight rather than for threads, since its calls per vertex divide by
// the blocks in lockstep (lockstep.h), but into blocks of no fewer than this many triangles: a
// seam vertex costs a traced curve's evaluations (about 20 on the torus of python/README.md),
// and a block of 250 triangles has about 30 seam vertices.
constexpr double kFewestTrianglesPerLockstepBlock = 250;
// A surface estimated below this many blocks is meshed by tracking alone: a cut costs more than
// it gains on a surface meshed in a few milliseconds.
constexpr double kFewestBlocks = 2;
// At most 16^3 = 4096 blocks: at 2500 triangles each, 10^7 triangles; beyond that blocks grow
// rather than multiply (their seams' share keeps falling).
constexpr int kMaxBlocksPerAxis = 16;
// A cut plane passes through the middle of a seed-grid cell (never through its nodes), moved by
// up to kCutShift cells from its share of the box where the surface grazes it: a plane nearly
// tangent to the surface cuts it in curves that bend sharply or nearly touch (tiny loops, two
// seams close together on one face), which the fronts on either side mesh badly.
constexpr int kCutShift = 2;
// Layouts tried before tracking alone when the surface grazes a block's edge (GrazedEdgeError):
// the cuts of each after the first moved by kLayoutShifts of a block from their shares of the box.
// A block edge (where two cut planes meet) that the surface touches between two of its samples
// leaves a seam with no corner to end at; another pair of planes meets it elsewhere. The random
// blobs as a numpy function at tolerance 1e-3 and factor 8, and a rounded cylinder at factor 8,
// were tracked alone for that, at 4-20 times the calls of blocks in lockstep.
constexpr std::array<double, 3> kLayoutShifts{0, 1.0 / 3, -1.0 / 3};
// A plane is good when, at every sample of it within one sample spacing of the surface, the
// surface's normal leans at least 30 degrees away from the plane's (the gradient's share in the
// plane is at least sin 30 = 0.5); otherwise the candidate that leans most is taken.
constexpr double kGoodLean = 0.5;
// Below this lean on every candidate the surface is tangent to the cut to rounding: the layout
// is refused. A near tangency is not: the lean is the least over the whole plane, and the blob
// fields of the topology sweep have one near many planes (with sin 5 degrees here, 30 of its runs
// were cut into blocks instead of 113, all 113 correct); a loop it leaves is found from the
// samples, or one smaller than their spacing is crossed by the fronts of the block that holds
// the rest of its surface, within kOutsideBlock of a step.
constexpr double kLeastLean = 1e-6;
// A candidate plane whose lean predicted from the seed grid (predicted_lean) is under this is
// sampled only if no other candidate is good: each sampled candidate is a plane of gradients (2
// samples a cell each way), though only the chosen one's values are kept. The bunny VIS-800 at
// factor 5 sampled eight planes, 32,000 gradients, a third of what its blocks cost over tracking
// alone; five were refused for grazing, three of them as the grid predicts. The prediction
// follows the samples' lean to a few hundredths on the fields of experiments/fields (up to 0.2
// above it on the MPU models, where it is less often under this); a good plane it called grazing
// would be passed over for the next good one, which none was on the 480 runs of the topology
// sweep, the 646 of the SDF sweep, 56 of experiments/fields and the 36 numpy models of
// python/README.md (the same meshes as sampling every candidate; the bunny at factor 5: 109,707
// -> 97,032 gradients, 0.35 -> 0.336 s on one thread).
constexpr double kSkipLean = 0.4;
// The seed grid's columns whose lean predicted_lean counts: those within this share of a cell of
// the surface (F over its gradient's length). A little inside half a cell, the reach of
// plane_lean's samples (half a cell apart, within one spacing): a plane half a cell from a face
// parallel to it (a rounded box's flat face on a grid node) was predicted to graze where its
// samples saw no surface, and a cut was moved that sampling every candidate kept.
constexpr double kPredictedBand = 0.4;
// Samples per seed-grid cell along a block edge (roots of F on the line) and across a cut plane
// (its grazing and the loops of the seams inside a face).
constexpr int kLineSamples = 4;
constexpr int kPlaneSamples = 2;
// A cut plane's sample is evaluated only near the surface as the seed grid sees it: not where the
// eight nodes of its grid cell have one sign and each is further from zero than this many times
// the largest change of F along the cell's edges. For F linear over the cell, that change is at
// least |grad F| h / sqrt 3, so the surface is more than sqrt 3 h from each node and more than
// (sqrt 3 - sqrt 3 / 2) h = 0.87 h from the sample: beyond the half cell within which plane_lean
// looks. Such a sample takes the nodes' sign (their mean) and no gradient; one beside an evaluated
// sample of the other sign is evaluated after all (a surface the grid does not see). The bunny
// VIS-800 at factor 5 sampled five planes of 3,500-4,200 gradients, a fifth of its evaluations
// in blocks; 47 % of the samples are evaluated now.
constexpr double kFarFromSurface = 3;
// Bisection steps for a root on a block edge: 2^-60 of a sample spacing, below rounding.
constexpr int kRootBisections = 60;
// Halvings of a block edge's sample spacing where F dips toward zero between two samples of one
// sign (both ends' slopes head for zero and their tangents reach it inside): the surface may
// cross the edge twice between them. The crowd of 200 Wyvill blobs at factor 3 crosses one edge
// at y = 0.0237 and 0.0507, between samples 0.041 apart, and each layout failed on the seam that
// reached it with no corner there. 2^-8 of a spacing is 1/1024 of a seed cell. A line's halvings
// are bounded by its samples, so that a field dipping everywhere costs at most twice its lines.
constexpr int kDipHalvings = 8;
// Newton steps onto a seam (F = 0 in the cut plane), and their tolerance as a share of the box
// diagonal (the tracker's projections converge to 1e-10 of it).
constexpr int kSeamNewtonSteps = 12;
constexpr double kSeamTolerance = 1e-10;
// A seam is traced in steps of this share of the target edge length at the point, halved while
// its tangent turns more than kTraceTurn radians a step (or Newton takes the step back), down to
// kShortestTraceStep of min_edge. A whole edge: each traced point costs a Hessian (its target)
// and a Newton projection, and resample puts the seam's vertices back on it by Newton, so a
// finer trace buys nothing but the targets between vertices. At a quarter of an edge the torus
// at factor 40 spent 0.17 Hessians and 0.44 value-and-gradient calls per mesh vertex tracing
// its seams (0.04 and 0.18 now), with the same angles and edge ratios at the walls.
constexpr double kTraceShare = 1.0;
constexpr double kTraceTurn = 0.3;
constexpr double kShortestTraceStep = 0.1;
// Traced points of the seams of one face: at most this many per estimated triangle of the mesh,
// and at least kFewestTracePoints. A bound on the work, far above what tracing takes: a seam is
// traced in steps of about an edge, and a block's seams, crossing a surface of
// about kTrianglesPerBlock triangles, hold about a hundred vertices.
constexpr double kTracePointsPerTriangle = 2;
constexpr std::size_t kFewestTracePoints = 100'000;
// A traced seam ends at the corner of its face's side that it crosses within this share of its
// last step or of min_edge, the larger (a corner is F = 0 on the side, the crossing its chord's
// intersection with it).
constexpr double kCornerReach = 0.5;
// A traced chord strays from its seam by its sagitta, under 0.04 of its length at a turn of
// kTraceTurn: a point of a seam within this share of a chord's length lies on the chord's seam.
constexpr double kChordStray = 0.1;
// A seam that leaves a corner within this cosine of the block edge's direction grazes the edge
// (it would run along the side, out of the face as soon as into it).
constexpr double kEdgeGraze = 1e-3;
// A chord's crossing with a side counts within this share of the side's length past its ends
// (rounding of the crossing's coordinates).
constexpr double kSideRounding = 1e-12;
// A loop closes where a chord passes within a step of its start, once it has gone this many steps.
constexpr double kLoopShortest = 3;
// A traced seam longer than this many times its face's perimeter has lost its way.
constexpr double kLongestSeam = 100;
// Seam vertices measured together by one thread of a thread-safe field (their Hessians and curvature).
constexpr std::size_t kSeamVertexSlice = 256;

Vec3 axis_vector(int a) { return Vec3::Unit(a); }

// The seed grid's cell of `layer` along axis a, at (ib, id) along the other two (b, d): the mean
// of its eight nodes where it is far from the surface (kFarFromSurface), NaN where it is not.
double far_cell_value(const SeedGrid& grid, int a, int layer, int ib, int id) {
  constexpr double kNear = std::numeric_limits<double>::quiet_NaN();
  std::array<int, 3> lo{};
  lo[a] = layer, lo[(a + 1) % 3] = ib, lo[(a + 2) % 3] = id;
  std::array<double, 8> v{};
  for (int corner = 0; corner < 8; ++corner) {
    v[static_cast<std::size_t>(corner)] = grid.value(lo[0] + (corner & 1), lo[1] + (corner >> 1 & 1), lo[2] + (corner >> 2 & 1));
    // sample_seed_grid's stand-ins for NaN and the infinities are no distance.
    if (std::abs(v[static_cast<std::size_t>(corner)]) == std::numeric_limits<double>::max()) return kNear;
  }
  double least = std::numeric_limits<double>::infinity(), change = 0, sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const double x = v[static_cast<std::size_t>(corner)];
    if ((x < 0) != (v[0] < 0)) return kNear;
    least = std::min(least, std::abs(x));
    sum += x;
    for (const int bit : {1, 2, 4})  // the cell's edges, each once from its lower end
      if (!(corner & bit)) change = std::max(change, std::abs(v[static_cast<std::size_t>(corner | bit)] - x));
  }
  return least > kFarFromSurface * change ? sum / 8 : kNear;
}

}  // namespace

PlaneSamples sample_plane(const Field& field, const SeedGrid& grid, int a, int layer, double c, int threads) {
  PlaneSamples s;
  s.a = a, s.b = (a + 1) % 3, s.d = (a + 2) % 3, s.c = c;
  const Box& box = field.bounds();
  const Vec3 size = box.size();
  s.nb = std::max(1, static_cast<int>(std::ceil(kPlaneSamples * size[s.b] / grid.h)));
  s.nd = std::max(1, static_cast<int>(std::ceil(kPlaneSamples * size[s.d] / grid.h)));
  s.sb = size[s.b] / s.nb, s.sd = size[s.d] / s.nd;
  s.origin = box.min;
  s.origin[a] = c;
  const std::size_t count = static_cast<std::size_t>(s.nb + 1) * (s.nd + 1);
  s.values.resize(count);
  s.gradients.assign(count, Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  // Each sample's cell column, and its value where that cell is far from the surface.
  const auto column = [&](int axis, double x) {
    return std::clamp(static_cast<int>(std::floor((x - grid.origin[axis]) / grid.h)), 0, grid.n[axis] - 1);
  };
  std::vector<double> far_value(static_cast<std::size_t>(grid.n[s.b]) * grid.n[s.d]);
  for (int id = 0; id < grid.n[s.d]; ++id)
    for (int ib = 0; ib < grid.n[s.b]; ++ib)
      far_value[static_cast<std::size_t>(id) * grid.n[s.b] + ib] = far_cell_value(grid, a, layer, ib, id);
  std::vector<char> evaluated(count, 0);
  std::vector<std::size_t> todo;
  for (int j = 0; j <= s.nd; ++j)
    for (int i = 0; i <= s.nb; ++i) {
      const Vec3 p = s.point(i, j);
      const double far = far_value[static_cast<std::size_t>(column(s.d, p[s.d])) * grid.n[s.b] + column(s.b, p[s.b])];
      const std::size_t k = s.index(i, j);
      if (std::isnan(far))
        todo.push_back(k);
      else
        s.values[k] = far;
    }
  // The samples in `todo` evaluated; then those not yet evaluated beside an evaluated one of the
  // other sign, until none is (a surface the grid did not see, reaching into its far samples).
  constexpr std::size_t kBlock = 512;
  std::vector<Vec3> points;
  std::vector<double> values;
  std::vector<Vec3> gradients;
  while (!todo.empty()) {
    points.clear();
    for (const std::size_t k : todo) {
      points.push_back(s.point(static_cast<int>(k % (s.nb + 1)), static_cast<int>(k / (s.nb + 1))));
      evaluated[k] = 1;
    }
    values.resize(points.size());
    gradients.resize(points.size());
    // On all cores for a thread-safe field, as the seed grid (each sample in its own slot).
    if (field.thread_safe() && points.size() > kBlock)
      detail::parallel_blocks(points.size(), kBlock, detail::worker_count(threads),
                              [&](std::size_t begin, std::size_t end, unsigned) {
                                field.values_gradients(points.data() + begin, values.data() + begin,
                                                       gradients.data() + begin, end - begin);
                              });
    else
      field.values_gradients(points.data(), values.data(), gradients.data(), points.size());
    for (std::size_t m = 0; m < todo.size(); ++m) s.values[todo[m]] = values[m], s.gradients[todo[m]] = gradients[m];
    std::vector<std::size_t> next;
    for (const std::size_t k : todo) {
      const int i = static_cast<int>(k % (s.nb + 1)), j = static_cast<int>(k / (s.nb + 1));
      const std::array<std::pair<int, int>, 4> around{{{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}}};
      for (const auto& [i2, j2] : around) {
        if (i2 < 0 || j2 < 0 || i2 > s.nb || j2 > s.nd) continue;
        const std::size_t k2 = s.index(i2, j2);
        if (evaluated[k2] || (s.values[k2] < 0) == (s.values[k] < 0)) continue;
        evaluated[k2] = 1;
        next.push_back(k2);
      }
    }
    // The next round's points in index order, whatever order the neighbours were met in.
    std::sort(next.begin(), next.end());
    todo = std::move(next);
  }
  return s;
}

namespace {

// The smallest lean (share of the gradient in the plane) over the samples within a spacing of
// the surface; 1 where none is.
double plane_lean(const PlaneSamples& s) {
  const double spacing = std::max(s.sb, s.sd);
  double lean = 1;
  for (std::size_t k = 0; k < s.values.size(); ++k) {
    const Vec3& g = s.gradients[k];
    const double gn = g.norm();
    if (!(gn > 0) || !std::isfinite(s.values[k]) || std::abs(s.values[k]) > spacing * gn) continue;
    lean = std::min(lean, std::sqrt(std::max(0.0, gn * gn - g[s.a] * g[s.a])) / gn);
  }
  return lean;
}

// The surface grazes a block's edge (a seam with no corner to end at): another layout may not.
class GrazedEdgeError : public CreaseLayoutError {
 public:
  using CreaseLayoutError::CreaseLayoutError;
};

struct Cuts {
  std::array<std::vector<double>, 3> walls;  // per axis: the box's min, the cuts, the box's max
  std::array<std::vector<PlaneSamples>, 3> planes;  // per axis, per cut
  int count(int a) const { return static_cast<int>(walls[a].size()) - 1; }
};

// The blocks along each axis: about kTrianglesPerBlock triangles each (fewer for a costly field),
// shared out in proportion to the box's sides. All ones where the surface is too small to cut.
std::array<int, 3> block_counts(const Field& field, bool costly, const SeedGridStage& seeds) {
  std::array<int, 3> n{1, 1, 1};
  const double per_block =
      costly ? std::clamp(seeds.estimated_triangles / static_cast<double>(kLockstepTasks),
                          kFewestTrianglesPerLockstepBlock, kTrianglesPerBlock)
             : kTrianglesPerBlock;
  const double blocks = seeds.estimated_triangles / per_block;
  if (blocks < kFewestBlocks) return n;
  const Vec3 size = field.bounds().size();
  const double side = std::cbrt(size.prod() / blocks);
  for (int a = 0; a < 3; ++a)
    n[a] = std::clamp(static_cast<int>(std::lround(size[a] / side)), 1, kMaxBlocksPerAxis);
  return n;
}

// The cuts along each axis (see kCutShift and kGoodLean); each plane keeps its samples.
Cuts choose_cuts(const Field& field, const SeedGrid& grid, const std::array<int, 3>& n, double offset, int threads,
                 const CancelToken& cancel) {
  Cuts cuts;
  const Box& box = field.bounds();
  for (int a = 0; a < 3; ++a) {
    cuts.walls[a].push_back(box.min[a]);
    int last = -1;  // the cell of the cut before: cuts stay in increasing cells, at least one apart
    for (int i = 1; i < n[a]; ++i) {
      const double ideal = box.min[a] + box.size()[a] * (i + offset) / n[a];
      const int cell = std::clamp(static_cast<int>(std::floor((ideal - grid.origin[a]) / grid.h)), 0, grid.n[a] - 1);
      // The candidates in order of preference: the first good one is taken, else the one that
      // leans most (the first of them). Those the grid predicts to graze are sampled last, only
      // if no other is good (kSkipLean).
      struct Candidate {
        int cell;
        double c, lean;  // lean: the samples', once sampled
        bool skipped;
        std::optional<PlaneSamples> samples;
      };
      std::vector<Candidate> candidates;
      for (int shift = 0; shift <= 2 * kCutShift; ++shift) {
        const int k = cell + (shift % 2 == 1 ? -(shift + 1) / 2 : shift / 2);  // 0, -1, +1, -2, +2
        if (k <= last || k > grid.n[a] - 1 - (n[a] - 1 - i)) continue;
        const double c = grid.origin[a] + (k + 0.5) * grid.h;
        if (!(c > box.min[a] && c < box.max[a])) continue;  // the grid's last layer may pass the box
        candidates.push_back({k, c, -1, predicted_lean(grid, box, a, k) < kSkipLean, {}});
      }
      const auto sample = [&](Candidate& m) {
        cancel.check("adaptive");
        m.samples = sample_plane(field, grid, a, m.cell, m.c, threads);
        m.lean = plane_lean(*m.samples);
      };
      Candidate* best = nullptr;
      for (Candidate& m : candidates) {
        if (m.skipped) continue;
        sample(m);
        if (m.lean >= kGoodLean) {
          best = &m;
          break;
        }
      }
      if (!best)
        for (Candidate& m : candidates) {
          if (!m.samples) sample(m);
          if (!best || m.lean > best->lean) best = &m;
          if (best->lean >= kGoodLean) break;
        }
      if (!best) throw CreaseLayoutError("adaptive: the box is too small for " + std::to_string(n[a]) + " blocks");
      if (best->lean < kLeastLean)
        throw CreaseLayoutError("adaptive: every cut plane near " + std::to_string(best->c) + " grazes the surface");
      last = best->cell;
      cuts.walls[a].push_back(best->c);
      cuts.planes[a].push_back(std::move(*best->samples));
    }
    cuts.walls[a].push_back(box.max[a]);
  }
  return cuts;
}

// Seam vertices: the corners first, then each face's seams' inner vertices. A face traces its
// own from `base` (the corners' count) up, as if they came right after the corners; mesh_blocks
// numbers them after the faces' before it.
struct SeamVertices {
  std::vector<Vec3> points;
  int base = 0;
  int add(const Vec3& p) {
    points.push_back(p);
    return base + static_cast<int>(points.size()) - 1;
  }
};

// A point where the surface crosses a block edge.
struct Corner {
  double t;  // coordinate along the edge's axis
  int vertex;
};

// The lines along which block walls meet: along axis `along`, at wall indices (i, j) of the two
// other axes in increasing axis order.
struct Lines {
  std::array<std::vector<std::vector<Corner>>, 3> roots;  // [along][i * (walls of second) + j]
  std::array<int, 3> stride{};
  const std::vector<Corner>& at(int along, int i, int j) const {
    return roots[along][static_cast<std::size_t>(i) * stride[along] + j];
  }
};

std::pair<int, int> other_axes(int a) { return {a == 0 ? 1 : 0, a == 2 ? 1 : 2}; }

// Every root of F on every line where interior walls meet (find_corners): sampled at
// kLineSamples per seed cell, each sign change bisected. A root on the box's own side (a line
// with a wall of the box) means the surface reaches the box there, which the layout refuses.
Lines find_corners(const Field& field, const Cuts& cuts, double cell, SeamVertices& sv, const CancelToken& cancel) {
  Lines lines;
  // A sign change of F between two samples of a line, in the order of the lines and the samples.
  struct Bracket {
    int along;
    std::size_t line;  // in lines.roots[along]
    Vec3 base;
    double lo, hi;
    bool negative_lo;  // F < 0 at lo
    Vec3 at(double t) const {
      Vec3 x = base;
      x[along] = t;
      return x;
    }
  };
  std::vector<Bracket> brackets;
  const Box& box = field.bounds();
  for (int along = 0; along < 3; ++along) {
    const auto [p, q] = other_axes(along);
    const int np = cuts.count(p), nq = cuts.count(q);
    lines.stride[along] = nq + 1;
    lines.roots[along].assign(static_cast<std::size_t>(np + 1) * (nq + 1), {});
    const int samples = std::max(2, static_cast<int>(std::ceil(kLineSamples * box.size()[along] / cell)));
    const double step = box.size()[along] / samples;
    std::vector<Vec3> points(static_cast<std::size_t>(samples) + 1);
    std::vector<double> values(points.size());
    std::vector<Vec3> gradients(points.size());
    for (int i = 0; i <= np; ++i)
      for (int j = 0; j <= nq; ++j) {
        const bool interior_i = i > 0 && i < np, interior_j = j > 0 && j < nq;
        if (!interior_i && !interior_j) continue;  // an edge of the box: no interior face has it
        cancel.check("adaptive");
        Vec3 base = box.min;
        base[p] = cuts.walls[p][static_cast<std::size_t>(i)];
        base[q] = cuts.walls[q][static_cast<std::size_t>(j)];
        const auto at = [&](double t) {
          Vec3 x = base;
          x[along] = t;
          return x;
        };
        for (int k = 0; k <= samples; ++k) points[static_cast<std::size_t>(k)] = at(box.min[along] + step * k);
        field.values_gradients(points.data(), values.data(), gradients.data(), points.size());
        const std::size_t line = static_cast<std::size_t>(i) * (nq + 1) + j;
        const auto finite_at = [&](double v, double t) {
          if (!std::isfinite(v))
            throw CreaseLayoutError("adaptive: the field is not finite on a block's edge near " + format_point(at(t)));
        };
        const auto bracket = [&](double lo, double hi, double flo) {
          if (!interior_i || !interior_j)
            throw CreaseLayoutError("adaptive: the surface reaches the box's side near " + format_point(at(lo)));
          brackets.push_back({along, line, base, lo, hi, flo < 0});
        };
        // Whether F may cross zero twice in [a, b] where it has one sign at both ends (slopes da,
        // db along the line): it heads for zero at a and comes back at b, and the tangent at each
        // end reaches zero inside.
        const auto dips = [](double a, double b, double fa, double fb, double da, double db) {
          const double s = fa < 0 ? -1 : 1;
          return s * da < 0 && s * db > 0 && std::abs(fa) < -s * da * (b - a) && std::abs(fb) < s * db * (b - a);
        };
        // Halves a dip, in order along the line, and brackets the sign changes it finds.
        int halvings_left = samples;
        const auto halve = [&](const auto& self, double a, double b, double fa, double fb, double da, double db,
                               int depth) -> void {
          if (depth == kDipHalvings || halvings_left == 0 || !dips(a, b, fa, fb, da, db)) return;
          --halvings_left;
          const double m = 0.5 * (a + b);
          Vec3 g;
          const double fm = field.value_gradient(at(m), g);
          finite_at(fm, m);
          const double dm = g[along];
          if ((fm < 0) != (fa < 0)) {
            bracket(a, m, fa);
            bracket(m, b, fm);
            return;
          }
          self(self, a, m, fa, fm, da, dm, depth + 1);
          self(self, m, b, fm, fb, dm, db, depth + 1);
        };
        for (int k = 0; k < samples; ++k) {
          const double lo = box.min[along] + step * k;
          const double flo = values[static_cast<std::size_t>(k)], fhi = values[static_cast<std::size_t>(k) + 1];
          finite_at(flo, lo);
          finite_at(fhi, lo);
          if ((flo < 0) != (fhi < 0)) {
            bracket(lo, lo + step, flo);
            continue;
          }
          halve(halve, lo, lo + step, flo, fhi, gradients[static_cast<std::size_t>(k)][along],
                gradients[static_cast<std::size_t>(k) + 1][along], 0);
        }
      }
  }
  // Every bracket bisected in lockstep, each round one batch of their middles: the same roots as
  // one after another, in kRootBisections calls of a costly field (Field::costly_calls) rather
  // than as many per corner.
  std::vector<Vec3> mids(brackets.size());
  std::vector<double> fm(brackets.size());
  for (int it = 0; it < kRootBisections && !brackets.empty(); ++it) {
    for (std::size_t r = 0; r < brackets.size(); ++r) mids[r] = brackets[r].at(0.5 * (brackets[r].lo + brackets[r].hi));
    field.values(mids.data(), fm.data(), mids.size());
    for (std::size_t r = 0; r < brackets.size(); ++r) {
      Bracket& b = brackets[r];
      const double mid = 0.5 * (b.lo + b.hi);
      if ((fm[r] < 0) == b.negative_lo) b.lo = mid;
      else b.hi = mid;
    }
  }
  for (const Bracket& b : brackets) {
    const double t = 0.5 * (b.lo + b.hi);
    lines.roots[b.along][b.line].push_back({t, sv.add(b.at(t))});
  }
  return lines;
}

// One face of a block, in the cut plane p[a] = c: the rectangle [b0, b1] x [d0, d1] of axes b, d.
struct Face {
  int a, b, d;
  int cut;                 // index of the plane in Cuts::planes[a]
  std::array<int, 2> cell; // the face's block indices along b and d
  double c, b0, b1, d0, d1;
  bool inside(const Vec3& x) const { return x[b] >= b0 && x[b] <= b1 && x[d] >= d0 && x[d] <= d1; }
};

// A corner on a face's side, with the direction into the face across that side.
struct FaceCorner {
  int vertex;
  Vec3 point, inward;
  int side;  // 0..3: d = d0, d = d1, b = b0, b = b1
  bool used = false;
};

// A seam of one face: vertices from corner to corner, or a loop.
struct Seam {
  std::vector<int> vertices;
  bool closed = false;
};

// SeamTracer::target looks across a black box's seams at these shares of the length the
// curvature asks for there: a rounded edge narrower than that length could lie between the two.
constexpr std::array<double, 2> kCrossReach{0.5, 1};
constexpr int kCrossRounds = 2;
// A traced point need not look across its seam where the point before it did and found nothing
// (no length under the curvature's own there), and its own length is within this share of that
// point's: the surface beside the seam neither changed nor pulled the length down. It takes that
// look's length plus kSeamGradation times their distance (as the grading that follows would),
// and the point after it looks again. Every look is four Hessians of differences (100 points of a
// Python function): looking from every point was 60 % of the torus callable's layout's points,
// whose curvature is the same along its seams; where the curvature changes along a seam (a twisted
// ellipsoid) or a rounded edge lies beside it, every point still looks. (Every second point, as a
// rule, let a twisted ellipsoid's seams at factor 3 pass 1.4 times as far from the surface.)
constexpr double kSteadyLength = 0.1;

struct SeamTracer {
  const Field& field;
  const Sizing& sizing;
  bool grading;
  bool looks_across;  // a costly field, whose C1 seams nothing describes (target)
  double tolerance;  // of the Newton steps onto a seam
  std::size_t& points_left;
  std::size_t points_bound;
  const CancelToken& cancel;

  // A point on a seam with F's gradient there: the last Newton step's, so that the seam's tangent
  // there costs no evaluation of its own (one round of a Python function's calls a traced step).
  struct OnSeam {
    Vec3 point;
    Vec3 gradient;
  };

  // x moved onto F = 0 within its plane (axis a fixed); nothing where Newton fails.
  std::optional<OnSeam> onto_seam(Vec3 x, int a) const {
    for (int it = 0; it < kSeamNewtonSteps; ++it) {
      Vec3 gradient;
      const double v = field.value_gradient(x, gradient);
      Vec3 g = gradient;
      g[a] = 0;
      const double gg = g.squaredNorm();
      if (!std::isfinite(v) || !(gg > 0)) return std::nullopt;
      if (std::abs(v) <= tolerance * std::sqrt(gg)) return OnSeam{x, gradient};
      x -= v / gg * g;
    }
    return std::nullopt;
  }

  // The seam's direction where F has gradient g: the plane's normal crossed with it, unit.
  static std::optional<Vec3> tangent_of(const Vec3& g, int a) {
    const Vec3 t = axis_vector(a).cross(g);
    const double n = t.norm();
    if (!(n > 0) || !std::isfinite(n)) return std::nullopt;
    return t / n;
  }
  std::optional<Vec3> tangent(const Vec3& x, int a) const { return tangent_of(field.gradient(x), a); }

  // The edge length the curvature asks for where the field has gradient g and Hessian h; none
  // where the gradient vanishes.
  std::optional<double> curvature_length(const Vec3& g, const Mat3& h) const {
    try {
      return edge_length(sizing, curvature_from_derivatives(g, h).min_radius);
    } catch (const NoSurfaceError&) {
      return std::nullopt;
    }
  }

  // The edge length the curvature asks for at x (min_edge where it has none).
  double curvature_target(const Vec3& x, Vec3* gradient = nullptr) const {
    Vec3 g;
    Mat3 h;
    field.gradient_hessian(x, g, h);
    if (gradient) *gradient = g;
    return curvature_length(g, h).value_or(sizing.min_edge);
  }

  // The last look across a seam being traced (target): where, the length x's own curvature asked
  // for and the length the look gave; and whether a point after it skipped its own look.
  struct LookAcross {
    Vec3 at;
    double own;
    double length;
    bool skipped = false;
  };

  // The edge length the surface asks for at x on a seam in a plane of axis a: its curvature and,
  // with grading, its C1 seams' (seam_edge_length), and for a costly field, whose C1 seams nothing
  // describes (a Python function: looks_across), the curvature across the seam: at the points
  // kCrossReach times x's own length to either side (on the surface, across the seam's tangent),
  // plus kSeamGradation times their distance. A cut near a black box's C1 seam and along it (a
  // rounded box's flat face 0.02 wide between the cut and a rounded edge) otherwise gave the
  // blocks' fronts starting there the flat face's long edges, and slivers where they met the
  // rounded edge. A trace passes `last`, its last look, to skip looks where nothing changes
  // (kSteadyLength).
  double target(const Vec3& x, int a, std::optional<LookAcross>* last = nullptr) const {
    Vec3 g;
    double len = curvature_target(x, &g);
    if (!grading) return len;
    len = std::min(len, seam_edge_length(field, sizing, x, len));
    if (!looks_across) return len;
    if (last && *last) {
      LookAcross& l = **last;
      if (!l.skipped && !(l.length < l.own) && std::abs(len - l.own) <= kSteadyLength * l.own) {
        l.skipped = true;
        return std::min(len, l.length + kSeamGradation * (x - l.at).norm());
      }
    }
    const double looked = look_across(x, a, g, len);
    if (last) *last = LookAcross{x, len, looked};
    return looked;
  }

  // `len` lowered to the curvature kCrossReach times it to either side of the seam through x (where
  // F has gradient g), plus kSeamGradation times their distance (target).
  double look_across(const Vec3& x, int a, const Vec3& g, double len) const {
    const Vec3 across = g.cross(axis_vector(a).cross(g));  // in the tangent plane, off the seam
    const double n = across.norm();
    if (!(n > 0) || !std::isfinite(n)) return len;
    // The probes of a round in one call (a Python function's calls, not its points, are its
    // cost), not projected: the level set through a point this near has the surface's curvature
    // there to within its distance from the surface (a distance field's offsets: 1 / (r + d)).
    // A round that lowers the length looks again within the new one (a rounded edge narrower than
    // the old reach could lie between its probes).
    for (int round = 0; round < kCrossRounds; ++round) {
      std::array<Vec3, 2 * kCrossReach.size()> at;
      for (std::size_t i = 0; i < at.size(); ++i)
        at[i] = x + (i % 2 == 0 ? -1.0 : 1.0) * kCrossReach[i / 2] * len / n * across;
      std::array<double, at.size()> values;
      std::array<Vec3, at.size()> gradients;
      std::array<Mat3, at.size()> hessians;
      field.gradients_hessians(at.data(), values.data(), gradients.data(), hessians.data(), at.size());
      const double before = len;
      for (std::size_t i = 0; i < at.size(); ++i)
        if (const std::optional<double> there = curvature_length(gradients[i], hessians[i]))
          len = std::min(len, *there + kSeamGradation * (at[i] - x).norm());
      if (!(len < before)) break;
    }
    return len;
  }

  // Traces the seam through `start` (on it) in direction `sign` of tangent(), until it leaves the
  // face (returns the crossing's side and point) or, for a loop, comes back to the start.
  struct Traced {
    std::vector<Vec3> points;
    std::vector<double> targets;
    int side = -1;  // the side it left by; -1 for a loop
    Vec3 exit;
    double last_step = 0;
  };
  // The first crossing of the chord x -> y (y outside the face) with a side of the face: the side,
  // the share of the chord and the point; side -1 when it crosses none.
  struct Exit {
    int side = -1;
    double u = 2;
    Vec3 at = Vec3::Zero();
  };
  static Exit leaves_by(const Face& f, const Vec3& x, const Vec3& y) {
    Exit out;
    const std::array<std::pair<int, double>, 4> sides{{{f.d, f.d0}, {f.d, f.d1}, {f.b, f.b0}, {f.b, f.b1}}};
    for (int s = 0; s < 4; ++s) {
      const auto [axis, wall] = sides[static_cast<std::size_t>(s)];
      const double den = y[axis] - x[axis];
      if (den == 0) continue;
      const double u = (wall - x[axis]) / den;
      if (u < 0 || u > 1 || u >= out.u) continue;
      const Vec3 z = x + u * (y - x);
      const int other = axis == f.b ? f.d : f.b;
      const double lo = axis == f.b ? f.d0 : f.b0, hi = axis == f.b ? f.d1 : f.b1;
      if (z[other] < lo - kSideRounding * (hi - lo) || z[other] > hi + kSideRounding * (hi - lo)) continue;
      out = {s, u, z};
    }
    return out;
  }
  Traced trace(const Face& f, const Vec3& start, double sign, bool loop) const {
    Traced out;
    std::optional<LookAcross> looked;
    out.points.push_back(start);
    out.targets.push_back(target(start, f.a, &looked));
    Vec3 x = start;
    // The tangent at x: the accepted step's own, measured when it was judged.
    std::optional<Vec3> t0 = tangent(x, f.a);
    double travelled = 0;
    for (;;) {
      if (points_left == 0)
        throw CreaseLayoutError("adaptive: the seams of a block's face pass " + std::to_string(points_bound) +
                                " traced points near " + format_point(x));
      --points_left;
      cancel.check("adaptive");  // an atomic load or two, beside a Newton step's evaluations
      if (!t0) throw CreaseLayoutError("adaptive: a seam's tangent vanishes near " + format_point(x));
      double step = kTraceShare * out.targets.back();
      std::optional<Vec3> next, t1;
      for (;;) {
        const std::optional<OnSeam> on = onto_seam(x + sign * step * *t0, f.a);
        next.reset();
        if (on) {
          next = on->point;
          t1 = tangent_of(on->gradient, f.a);
          // A step must land between half and twice its length on: where Newton brings it back
          // to x (a crease meshed as smooth, the blended block with creases ignored), the trace
          // stood still for 10^5 steps.
          const double moved = (*next - x).norm();
          // Nor may the first step from a corner leave by the corner itself: where the seam turns
          // back within a step (a neck 0.027 wide crossing a block's edge, steps of 0.033), its
          // chord left the face at its start and the seam ended there with no corner to end at.
          const bool back_out = out.points.size() == 1 && !f.inside(*next) && leaves_by(f, x, *next).u <= kSideRounding;
          if (t1 && t1->dot(*t0) >= std::cos(kTraceTurn) && moved >= 0.5 * step && moved <= 2 * step && !back_out)
            break;
        }
        step *= 0.5;
        if (step < kShortestTraceStep * sizing.min_edge)
          throw CreaseLayoutError("adaptive: a seam turns too sharply to trace near " + format_point(x) +
                                  " (a crease, or the surface grazing the wall)");
      }
      const Vec3 y = *next;
      if (!f.inside(y)) {
        const Exit e = leaves_by(f, x, y);
        if (e.side < 0) throw CreaseLayoutError("adaptive: a seam leaves its face at no side near " + format_point(y));
        out.side = e.side;
        out.exit = e.at;
        out.last_step = (y - x).norm();
        return out;
      }
      travelled += (y - x).norm();
      if (travelled > kLongestSeam * 2 * (f.b1 - f.b0 + f.d1 - f.d0))
        throw CreaseLayoutError("adaptive: a seam traced from " + format_point(start) + " does not end");
      if (loop && travelled > kLoopShortest * step) {
        const Vec3 u = y - x;
        const double s = std::clamp((start - x).dot(u) / u.squaredNorm(), 0.0, 1.0);
        if ((x + s * u - start).norm() < step) return out;  // the chord passes the start
      }
      out.points.push_back(y);
      out.targets.push_back(target(y, f.a, &looked));
      x = y;
      t0 = t1;
    }
  }
};

// Targets h along a polyline (a loop when `closed`) graded so that none exceeds another's plus
// kSeamGradation times the length between them along it: a sweep each way (twice round a loop).
// A black box's C1 seam (a rounded box's flat face meeting its rounded edge) tells no sizing where
// it is (Field::smooth_sides), so the targets jump there from the flat side's to the rounded
// edge's; vertices spaced by them left a few long seam edges beside short ones, and the blocks'
// fronts started from them with slivers.
void grade_along(const std::vector<Vec3>& points, bool closed, std::vector<double>& h) {
  const std::size_t n = points.size();
  if (n < 2) return;
  const std::size_t steps = closed ? 2 * n : n - 1;
  const auto relax = [&](std::size_t from, std::size_t to) {
    h[to] = std::min(h[to], h[from] + kSeamGradation * (points[to] - points[from]).norm());
  };
  for (std::size_t k = 0; k < steps; ++k) relax(k % n, (k + 1) % n);
  // Back the other way: from n - 1 (from 0, then n - 1, round a loop).
  const std::size_t top = closed ? n : n - 1;
  for (std::size_t k = 0; k < steps; ++k) relax((top + n - k % n) % n, (top + n - 1 - k % n) % n);
}

// The polyline's vertices about one target apart (equal steps of the integral of ds / target,
// the target also bounded by the seam's own turning), moved onto the seam. `first` and `last`
// are the corners' vertices of an open seam (ends of `points`), -1 for a loop.
Seam resample(const SeamTracer& tracer, const Face& f, const std::vector<Vec3>& points, std::vector<double> h,
              int first, int last, SeamVertices& sv) {
  Seam out;
  out.closed = first < 0;
  const std::size_t n = points.size();
  const std::size_t segments = out.closed ? n : n - 1;
  const auto at = [&](std::size_t i) -> const Vec3& { return points[i % n]; };
  for (std::size_t i = 0; i < n; ++i) {
    const bool interior = out.closed || (i > 0 && i + 1 < n);
    if (!interior) continue;
    const Vec3 u = points[i] - at(i + n - 1), w = at(i + 1) - points[i];
    const double turn = std::atan2(u.cross(w).norm(), u.dot(w));
    if (turn > 0) h[i] = std::min(h[i], edge_length(tracer.sizing, 0.5 * (u.norm() + w.norm()) / turn));
    h[i] = std::max(h[i], tracer.sizing.min_edge);
  }
  if (tracer.grading) grade_along(points, out.closed, h);
  std::vector<double> cumulative(segments + 1, 0.0);
  for (std::size_t j = 0; j < segments; ++j)
    cumulative[j + 1] = cumulative[j] + (at(j + 1) - at(j)).norm() * 0.5 * (1 / h[j] + 1 / h[(j + 1) % n]);
  const double total = cumulative.back();
  const std::size_t edges =
      std::max(out.closed ? kMinLoopEdges : kMinOpenEdges, static_cast<std::size_t>(std::ceil(total - 1e-9)));
  if (!out.closed) out.vertices.push_back(first);
  std::size_t j = 0;
  for (std::size_t k = out.closed ? 0 : 1; k < edges; ++k) {
    const double s = total * static_cast<double>(k) / static_cast<double>(edges);
    while (j + 1 < segments && cumulative[j + 1] < s) ++j;
    const double span = cumulative[j + 1] - cumulative[j];
    const double t = span > 0 ? std::clamp((s - cumulative[j]) / span, 0.0, 1.0) : 0.0;
    const Vec3 guess = at(j) + t * (at(j + 1) - at(j));
    std::optional<Vec3> x;
    if (k == 0) {
      x = points[0];
    } else if (const auto on = tracer.onto_seam(guess, f.a)) {
      x = on->point;
    }
    if (!x || (*x - guess).norm() > 0.5 * std::max(h[j], h[(j + 1) % n]))
      throw CreaseLayoutError("adaptive: a seam vertex could not be put on its seam near " + format_point(guess));
    out.vertices.push_back(sv.add(*x));
  }
  if (!out.closed) out.vertices.push_back(last);
  return out;
}

// The seam vertices' targets graded along the seams as grade_along grades the traced points'
// (none over another's plus kSeamGradation times the seam's length between them), through the
// corners from one face's seams to the next: shortest paths from every vertex at once. The
// blocks' trackers take the seam vertices' targets as their fronts' (Tracker::Placed::seam_target),
// which must agree with the seams' spacing.
void grade_seam_targets(const std::vector<std::vector<Seam>>& face_seams, const std::vector<Vec3>& points,
                        const Sizing& sizing, std::vector<Tracker::Placed>& placed) {
  const std::size_t n = placed.size();
  std::vector<std::vector<int>> next(n);
  for (const auto& seams : face_seams)
    for (const Seam& s : seams) {
      const std::size_t m = s.vertices.size();
      for (std::size_t i = 0; i + 1 < m + (s.closed ? 1 : 0); ++i) {
        const int a = s.vertices[i], b = s.vertices[(i + 1) % m];
        next[static_cast<std::size_t>(a)].push_back(b);
        next[static_cast<std::size_t>(b)].push_back(a);
      }
    }
  std::vector<double> own(n), target(n);
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (std::size_t v = 0; v < n; ++v) {
    own[v] = target[v] = std::min(edge_length(sizing, placed[v].curvature.min_radius), placed[v].seam_target);
    queue.emplace(target[v], static_cast<int>(v));
  }
  while (!queue.empty()) {
    const auto [t, v] = queue.top();
    queue.pop();
    if (t > target[static_cast<std::size_t>(v)]) continue;
    for (const int u : next[static_cast<std::size_t>(v)]) {
      const double reach =
          t + kSeamGradation * (points[static_cast<std::size_t>(u)] - points[static_cast<std::size_t>(v)]).norm();
      if (reach < target[static_cast<std::size_t>(u)]) {
        target[static_cast<std::size_t>(u)] = reach;
        queue.emplace(reach, u);
      }
    }
  }
  // Only where lowered: elsewhere seam_target stays what it was (infinite where no C1 seam is near).
  for (std::size_t v = 0; v < n; ++v)
    if (target[v] < own[v]) placed[v].seam_target = target[v];
}

// The seams of face f: from each corner on its sides to the corner where it leaves, then a loop
// through each crossing of the plane's samples inside the face that no seam passes near.
// `corners`: the corners' points (SeamVertices::points of find_corners); the seams' own vertices
// go to `own`.
std::vector<Seam> trace_face(const SeamTracer& tracer, const Face& f, const PlaneSamples& plane, const Lines& lines,
                             const std::vector<Vec3>& corners_at, SeamVertices& own) {
  std::vector<FaceCorner> corners;
  {
    // Sides d = d0, d = d1 run along b; b = b0, b = b1 along d. Lines are indexed by the wall
    // indices of the two other axes in increasing axis order.
    const auto collect = [&](int along, int side, int wall_index, double lo, double hi, const Vec3& inward) {
      const auto [p, q] = other_axes(along);
      const int ip = p == f.a ? f.cut + 1 : wall_index, iq = q == f.a ? f.cut + 1 : wall_index;
      for (const Corner& c : lines.at(along, ip, iq))
        if (c.t > lo && c.t < hi) {
          const Vec3& x = corners_at[static_cast<std::size_t>(c.vertex)];
          corners.push_back({c.vertex, x, inward, side});
        }
    };
    const int jb = f.cell[0], jd = f.cell[1];
    collect(f.b, 0, jd, f.b0, f.b1, axis_vector(f.d));
    collect(f.b, 1, jd + 1, f.b0, f.b1, -axis_vector(f.d));
    collect(f.d, 2, jb, f.d0, f.d1, axis_vector(f.b));
    collect(f.d, 3, jb + 1, f.d0, f.d1, -axis_vector(f.b));
  }
  std::vector<Seam> seams;
  std::vector<std::vector<Vec3>> traced;  // every traced polyline, for the loop search
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (corners[i].used) continue;
    const FaceCorner& from = corners[i];
    const std::optional<Vec3> t = tracer.tangent(from.point, f.a);
    if (!t || std::abs(t->dot(from.inward)) < kEdgeGraze)
      throw GrazedEdgeError("adaptive: the surface grazes a block's edge near " + format_point(from.point));
    const double sign = t->dot(from.inward) > 0 ? 1 : -1;
    SeamTracer::Traced tr = tracer.trace(f, from.point, sign, false);
    // The corner it ends at: on the side it left by, the nearest to the crossing, unused.
    int end = -1;
    double best = kCornerReach * std::max(tr.last_step, tracer.sizing.min_edge);
    for (std::size_t k = 0; k < corners.size(); ++k) {
      if (k == i || corners[k].side != tr.side) continue;
      const double dist = (corners[k].point - tr.exit).norm();
      if (dist < best) best = dist, end = static_cast<int>(k);
    }
    if (end < 0 || corners[static_cast<std::size_t>(end)].used)
      throw GrazedEdgeError("adaptive: a seam reaches a block's edge where no corner was found near " +
                            format_point(tr.exit) + " (the surface grazes the edge)");
    corners[i].used = corners[static_cast<std::size_t>(end)].used = true;
    tr.points.push_back(corners[static_cast<std::size_t>(end)].point);
    tr.targets.push_back(tracer.target(tr.points.back(), f.a));
    seams.push_back(
        resample(tracer, f, tr.points, tr.targets, from.vertex, corners[static_cast<std::size_t>(end)].vertex, own));
    traced.push_back(std::move(tr.points));
  }
  // Loops: every sample edge with a sign change inside the face is crossed by the seam through
  // it. One that no traced chord crosses starts a loop from its crossing moved onto the seam,
  // unless that point lies on a traced seam (within kChordStray of a chord: the chord missed
  // the edge near its end).
  const auto cross2 = [&](const Vec3& u, const Vec3& w) { return u[f.b] * w[f.d] - u[f.d] * w[f.b]; };
  const auto crossed = [&](const Vec3& p, const Vec3& q) {
    for (const std::vector<Vec3>& line : traced)
      for (std::size_t k = 0; k + 1 < line.size(); ++k) {
        const Vec3 &x = line[k], &y = line[k + 1];
        const double s1 = cross2(q - p, x - p), s2 = cross2(q - p, y - p);
        const double s3 = cross2(y - x, p - x), s4 = cross2(y - x, q - x);
        if (((s1 <= 0 && s2 >= 0) || (s1 >= 0 && s2 <= 0)) && ((s3 <= 0 && s4 >= 0) || (s3 >= 0 && s4 <= 0))) return true;
      }
    return false;
  };
  // Whether z lies within `reach` plus kChordStray of a chord's length of a traced chord.
  const auto on_traced = [&](const Vec3& z, double reach) {
    for (const std::vector<Vec3>& line : traced)
      for (std::size_t k = 0; k + 1 < line.size(); ++k) {
        const Vec3 u = line[k + 1] - line[k];
        const double len2 = u.squaredNorm();
        const double s = len2 > 0 ? std::clamp((z - line[k]).dot(u) / len2, 0.0, 1.0) : 0.0;
        if ((line[k] + s * u - z).norm() <= reach + kChordStray * std::sqrt(len2)) return true;
      }
    return false;
  };
  const double spacing = std::max(plane.sb, plane.sd);
  const int i0 = std::max(0, static_cast<int>(std::floor((f.b0 - plane.origin[f.b]) / plane.sb)));
  const int i1 = std::min(plane.nb, static_cast<int>(std::ceil((f.b1 - plane.origin[f.b]) / plane.sb)));
  const int j0 = std::max(0, static_cast<int>(std::floor((f.d0 - plane.origin[f.d]) / plane.sd)));
  const int j1 = std::min(plane.nd, static_cast<int>(std::ceil((f.d1 - plane.origin[f.d]) / plane.sd)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i)
      for (int dir = 0; dir < 2; ++dir) {
        const int i2 = i + (dir == 0), j2 = j + (dir == 1);
        if (i2 > plane.nb || j2 > plane.nd) continue;
        const double va = plane.values[plane.index(i, j)], vb = plane.values[plane.index(i2, j2)];
        if (!std::isfinite(va) || !std::isfinite(vb) || (va < 0) == (vb < 0)) continue;
        const Vec3 p = plane.point(i, j), q = plane.point(i2, j2);
        const Vec3 x = p + va / (va - vb) * (q - p);
        if (!f.inside(x) || crossed(p, q)) continue;
        std::optional<Vec3> start;
        if (const auto on = tracer.onto_seam(x, f.a)) start = on->point;
        if (!start)
          throw CreaseLayoutError("adaptive: a crossing of a block's wall could not be put on its seam near " +
                                  format_point(x));
        if (on_traced(*start, 0)) continue;
        // Moved out of the face by Newton: a crossing next to a side, on the seam that leaves by
        // that side if one was traced within a sample spacing of it.
        if (!f.inside(*start) && on_traced(x, spacing)) continue;
        // Else the surface passes by a corner of the face, nearly through the block's edge there: a
        // graze, which another layout's planes may miss (the crowd of 200 blobs at factor 3 meshes
        // in blocks on its third layout; tracked alone before).
        if (!f.inside(*start))
          throw GrazedEdgeError("adaptive: a seam crossing a block's wall near " + format_point(x) +
                                  " was not traced from a corner");
        SeamTracer::Traced tr = tracer.trace(f, *start, 1, true);
        if (tr.side >= 0)
          throw GrazedEdgeError("adaptive: a seam leaves its face where no corner was found near " +
                                format_point(tr.exit) + " (the surface grazes a block's edge)");
        if (tr.points.size() < 3) throw CreaseLayoutError("adaptive: a seam loop too small to mesh near " + format_point(x));
        seams.push_back(resample(tracer, f, tr.points, tr.targets, -1, -1, own));
        tr.points.push_back(tr.points.front());  // the closing chord too, for the crossings it makes
        traced.push_back(std::move(tr.points));
      }
  return seams;
}

// A seam's chord and the seam's tangent at its middle vertex agree in direction by at least
// this cosine (they are nearly parallel: a chord of a sampled seam turns by less than a radian).
constexpr double kOrientMargin = 0.1;

// One side of a seam as a block's boundary: vertices with the block's patch on the left seen
// from outside.
struct SeamDart {
  std::vector<int> vertices;
  int from = -1, to = -1;  // corner vertices of an open seam
};

// The vertex of a seam where orient() measures its direction.
std::size_t middle(const Seam& s) { return s.closed ? 0 : s.vertices.size() / 2; }

// The two darts of a seam of face f: the first for the block below the plane, the second above.
// With the gradient g at a vertex, the direction a x g has the side p[a] > c on its left seen
// from outside (g x (a x g) leans along +a). `g`: the gradient at the seam's middle() vertex.
std::array<SeamDart, 2> orient(const Face& f, const Seam& s, const SeamVertices& sv, const Vec3& g) {
  const std::size_t n = s.vertices.size();
  const std::size_t m = middle(s);
  const Vec3& x = sv.points[static_cast<std::size_t>(s.vertices[m])];
  const Vec3 dir = sv.points[static_cast<std::size_t>(s.vertices[(m + 1) % n])] -
                   sv.points[static_cast<std::size_t>(s.vertices[(m + n - 1) % n])];
  const Vec3 t = axis_vector(f.a).cross(g);
  const double along_t = dir.dot(t);
  if (!(std::abs(along_t) > kOrientMargin * dir.norm() * t.norm()))
    throw CreaseLayoutError("adaptive: a seam's direction is unclear near " + format_point(x));
  const bool along = along_t > 0;
  SeamDart up{s.vertices, s.closed ? -1 : s.vertices.front(), s.closed ? -1 : s.vertices.back()};
  SeamDart down = up;
  std::reverse(down.vertices.begin(), down.vertices.end());
  std::swap(down.from, down.to);
  if (!along) std::swap(up, down);
  return {std::move(down), std::move(up)};
}

// A block's boundary cycles: loops as they are, open darts joined at their corners.
std::vector<std::vector<int>> block_cycles(const std::vector<SeamDart>& darts) {
  std::vector<std::vector<int>> cycles;
  std::vector<bool> used(darts.size(), false);
  const auto next_from = [&](int corner) {
    int found = -1;
    for (std::size_t k = 0; k < darts.size(); ++k)
      if (darts[k].from == corner) {
        if (found >= 0) throw CreaseLayoutError("adaptive: two seams of a block leave one corner");
        found = static_cast<int>(k);
      }
    return found;
  };
  for (std::size_t i = 0; i < darts.size(); ++i) {
    if (used[i]) continue;
    if (darts[i].from < 0) {
      used[i] = true;
      cycles.push_back(darts[i].vertices);
      continue;
    }
    std::vector<int> cycle;
    std::size_t k = i;
    for (std::size_t guard = 0; guard <= darts.size(); ++guard) {
      if (used[k]) throw CreaseLayoutError("adaptive: a block's seams do not close into a cycle");
      used[k] = true;
      const SeamDart& d = darts[k];
      cycle.insert(cycle.end(), d.vertices.begin(), d.vertices.end() - 1);  // its end starts the next
      const int next = next_from(d.to);
      if (next < 0) throw CreaseLayoutError("adaptive: a block's seam ends at a corner no other leaves");
      if (static_cast<std::size_t>(next) == i) break;
      k = static_cast<std::size_t>(next);
    }
    cycles.push_back(std::move(cycle));
  }
  return cycles;
}

// Whether `error` holds an E (a block's kink, BlackBoxKinkError; a stop, CancelledError).
template <class E>
bool holds(const std::exception_ptr& error) {
  if (!error) return false;
  try {
    std::rethrow_exception(error);
  } catch (const E&) {
    return true;
  } catch (...) {
    return false;
  }
}
}  // namespace

BlockMeshing mesh_blocks(const Field& field, const AdaptiveOptions& options, const Settings& settings,
                         const SeedGridStage& seeds, const QualityOptions* repair, std::uint64_t shuffle) {
  const auto start = Clock::now();
  BlockMeshing out;
  out.report.estimated_triangles = seeds.estimated_triangles;
  // Whether the layout is a costly field's (Field::costly_calls, asked once here): its blocks' sizes,
  // and its seams looking across themselves (SeamTracer::looks_across).
  const bool costly = field.costly_calls();
  const std::array<int, 3> n = block_counts(field, costly, seeds);
  if (n[0] * n[1] * n[2] < 2) return out;
  out.report.blocks = n;
  // Layouts from kLayoutShifts in turn while the surface grazes a block's edge; one whose cuts
  // came out as an earlier one's (blocks a few seed cells wide, or the same planes chosen near
  // both shifts) is not traced again.
  std::vector<std::array<std::vector<double>, 3>> tried;
  std::string grazed;
  for (std::size_t layout = 0;; ++layout) {
    out.report.layouts = layout + 1;
    try {
      const Cuts cuts = choose_cuts(field, seeds.grid, n, kLayoutShifts[layout], options.threads, options.cancel);
      if (std::find(tried.begin(), tried.end(), cuts.walls) != tried.end()) throw GrazedEdgeError(grazed);
      tried.push_back(cuts.walls);
      for (int a = 0; a < 3; ++a) out.report.cuts[a].assign(cuts.walls[a].begin() + 1, cuts.walls[a].end() - 1);
      SeamVertices sv;
      const Lines lines = find_corners(field, cuts, seeds.grid.h, sv, options.cancel);
      out.report.corners = sv.points.size();
      const std::size_t points_bound = std::max(
          kFewestTracePoints, static_cast<std::size_t>(kTracePointsPerTriangle * seeds.estimated_triangles));
      std::vector<Face> faces;
      for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, d = (a + 2) % 3;
        for (int cut = 0; cut + 1 < cuts.count(a); ++cut)
          for (int jd = 0; jd < cuts.count(d); ++jd)
            for (int jb = 0; jb < cuts.count(b); ++jb)
              faces.push_back({a, b, d, cut, {jb, jd}, cuts.walls[a][static_cast<std::size_t>(cut) + 1],
                               cuts.walls[b][static_cast<std::size_t>(jb)], cuts.walls[b][static_cast<std::size_t>(jb) + 1],
                               cuts.walls[d][static_cast<std::size_t>(jd)], cuts.walls[d][static_cast<std::size_t>(jd) + 1]});
      }
      // Each face's seams, from the corners alone: one after another, or in lockstep for a costly field.
      const std::size_t ncorners = sv.points.size();
      std::vector<std::vector<Seam>> face_seams(faces.size());
      std::vector<SeamVertices> face_vertices(faces.size());
      // A Python function's C1 seams are known to nothing (Field::smooth_sides), promised smooth or
      // not (smooth: no crease; a rounded box is C1); a cheap field's are described by its model or
      // absent, and looking across every traced point would cost it more evaluations than its seams
      // take now.
      const bool looks_across = settings.grading && costly;
      // Only the lowest failed face's error is rethrown (in face order, on any thread count), so a
      // face that fails stops the faces after it at their next traced point (each face's cancel
      // token, linked to the run's): a layout that fails costs no more than it must. (The clipped
      // gyroid as a numpy function, its faces in lockstep, traced on for 40,000 calls past the
      // first seam that turned too sharply.)
      const bool faces_in_lockstep = field.costly_calls();
      std::vector<CancelToken> face_stops(faces.size());
      for (CancelToken& t : face_stops) t = options.cancel.linked();
      const auto trace_one = [&](const Field& on, std::size_t i) {
        face_stops[i].check("adaptive");
        std::size_t points_left = points_bound;
        const SeamTracer tracer{on,          settings.sizing, settings.grading, looks_across,
                                kSeamTolerance * settings.diagonal, points_left, points_bound, face_stops[i]};
        const Face& f = faces[i];
        face_vertices[i].base = static_cast<int>(ncorners);
        try {
          face_seams[i] = trace_face(tracer, f, cuts.planes[f.a][static_cast<std::size_t>(f.cut)], lines, sv.points,
                                     face_vertices[i]);
        } catch (...) {
          for (std::size_t later = i + 1; later < faces.size(); ++later) face_stops[later].cancel();
          throw;
        }
      };
      if (faces_in_lockstep) {
        const LockstepReport lockstep =
            run_in_lockstep(field, faces.size(), trace_one);
        out.report.lockstep_tasks = lockstep.carriers;
        out.report.lockstep_batches += lockstep.batches;
      } else if (field.thread_safe()) {
        // On all cores, each face into its own slot (an error is the first face's in face order).
        detail::parallel_blocks(faces.size(), 1, detail::worker_count(options.threads),
                                [&](std::size_t begin, std::size_t end, unsigned) {
                                  for (std::size_t i = begin; i < end; ++i) trace_one(field, i);
                                });
      } else {
        for (std::size_t i = 0; i < faces.size(); ++i) trace_one(field, i);
      }
      // Their vertices numbered in face order, and every seam's middle gradient in one batch.
      std::vector<Vec3> middles;
      for (std::size_t i = 0; i < faces.size(); ++i) {
        const int shift = static_cast<int>(sv.points.size() - ncorners);
        for (Seam& s : face_seams[i])
          for (int& v : s.vertices)
            if (v >= static_cast<int>(ncorners)) v += shift;
        sv.points.insert(sv.points.end(), face_vertices[i].points.begin(), face_vertices[i].points.end());
        for (const Seam& s : face_seams[i]) middles.push_back(sv.points[static_cast<std::size_t>(s.vertices[middle(s)])]);
      }
      std::vector<double> middle_values(middles.size());
      std::vector<Vec3> middle_gradients(middles.size());
      field.values_gradients(middles.data(), middle_values.data(), middle_gradients.data(), middles.size());
      const auto block_index = [&](int i, int j, int k) { return static_cast<std::size_t>((k * n[1] + j) * n[0] + i); };
      const std::size_t nblocks = static_cast<std::size_t>(n[0]) * n[1] * n[2];
      std::vector<std::vector<SeamDart>> darts(nblocks);
      for (std::size_t i = 0, m = 0; i < faces.size(); ++i) {
        const Face& f = faces[i];
        for (const Seam& s : face_seams[i]) {
          std::array<int, 3> lo{}, hi{};
          lo[f.a] = f.cut, hi[f.a] = f.cut + 1;
          lo[f.b] = hi[f.b] = f.cell[0];
          lo[f.d] = hi[f.d] = f.cell[1];
          auto [below, above] = orient(f, s, sv, middle_gradients[m++]);
          darts[block_index(lo[0], lo[1], lo[2])].push_back(std::move(below));
          darts[block_index(hi[0], hi[1], hi[2])].push_back(std::move(above));
          ++out.report.seams;
        }
      }
      // Every corner ends two seams of each of its four blocks' faces: one unused means a seam
      // the faces' tracing missed.
      std::vector<int> ends(out.report.corners, 0);
      for (const auto& ds : darts)
        for (const SeamDart& dt : ds)
          if (dt.from >= 0) ++ends[static_cast<std::size_t>(dt.from)], ++ends[static_cast<std::size_t>(dt.to)];
      for (std::size_t c = 0; c < out.report.corners; ++c)
        if (ends[c] != 8)
          throw CreaseLayoutError("adaptive: a block corner ends " + std::to_string(ends[c] / 2) +
                                  " seams instead of 4 near " + format_point(sv.points[c]));
      out.report.seam_vertices = sv.points.size();
      // The seam vertices measured once, for both blocks that start from them.
      std::vector<Tracker::Placed> placed(sv.points.size());
      {
        std::vector<double> values(sv.points.size());
        std::vector<Vec3> gradients(sv.points.size());
        std::vector<Mat3> hessians(sv.points.size());
        // In one batch, or in slices on all cores for a thread-safe field (each into its own slots).
        const auto measure = [&](std::size_t begin, std::size_t end, unsigned) {
          field.gradients_hessians(sv.points.data() + begin, values.data() + begin, gradients.data() + begin,
                                   hessians.data() + begin, end - begin);
          for (std::size_t v = begin; v < end; ++v) {
            placed[v] = {sv.points[v], curvature_from_derivatives(gradients[v], hessians[v]),
                         step_to_critical_point(gradients[v], hessians[v])};
            if (settings.grading)
              placed[v].seam_target = seam_edge_length(field, settings.sizing, sv.points[v],
                                                       edge_length(settings.sizing, placed[v].curvature.min_radius));
          }
        };
        if (field.thread_safe())
          detail::parallel_blocks(sv.points.size(), kSeamVertexSlice, detail::worker_count(options.threads), measure);
        else
          measure(0, sv.points.size(), 0);
        if (settings.grading) grade_seam_targets(face_seams, sv.points, settings.sizing, placed);
      }
      std::vector<std::vector<std::vector<int>>> cycles(nblocks);
      for (std::size_t blk = 0; blk < nblocks; ++blk) cycles[blk] = block_cycles(darts[blk]);
      out.report.layout_seconds = seconds_since(start);

      // The blocks, largest first (by their seam vertices), each into its own slot.
      std::vector<std::size_t> order;
      for (std::size_t blk = 0; blk < nblocks; ++blk)
        if (!cycles[blk].empty()) order.push_back(blk);
      const auto weight = [&](std::size_t blk) {
        std::size_t w = 0;
        for (const auto& c : cycles[blk]) w += c.size();
        return w;
      };
      std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return weight(x) > weight(y); });
      if (shuffle != 0) std::shuffle(order.begin(), order.end(), std::mt19937_64(shuffle));
      // Block blk's box: its lowest and highest corners.
      const auto block_box = [&](std::size_t blk) {
        const int bi = static_cast<int>(blk % n[0]), bj = static_cast<int>(blk / n[0] % n[1]),
                  bk = static_cast<int>(blk / (static_cast<std::size_t>(n[0]) * n[1]));
        return std::pair<Vec3, Vec3>{Vec3(cuts.walls[0][bi], cuts.walls[1][bj], cuts.walls[2][bk]),
                                     Vec3(cuts.walls[0][bi + 1], cuts.walls[1][bj + 1], cuts.walls[2][bk + 1])};
      };
      // Each block's cancel token, linked to the run's. A black box's kink in a block ends the run
      // with the lowest such block's error (below), so a kink stops the blocks after its own in
      // block order at their next poll, whatever order they run in: their parts could change
      // nothing. (The clipped gyroid as a numpy function, 64 blocks in lockstep, ran on for 43,000
      // calls past its first kink when the layout did not meet one first.)
      std::vector<CancelToken> stops(nblocks);
      for (CancelToken& t : stops) t = settings.cancel.linked();
      // Block blk's task: all its tracker needs besides the field.
      const auto block_task = [&](std::size_t blk) {
        BlockTask task{blk, settings, seeds.estimated_area, {}, {}, {}, {}, options.check_self_intersections};
        task.settings.cancel = stops[blk];
        std::tie(task.lo, task.hi) = block_box(blk);
        for (const std::vector<int>& cycle : cycles[blk]) {
          std::vector<Tracker::Placed>& loop = task.loops.emplace_back();
          for (const int v : cycle) loop.push_back(placed[static_cast<std::size_t>(v)]);
        }
        if (repair) task.repair = *repair, task.repair->cancel = stops[blk];
        return task;
      };
      std::vector<BlockPart> parts(nblocks);
      // Block blk run here (on any thread: each its own slot, and cancel() is one atomic store).
      const auto run_here = [&](const Field& on, std::size_t blk) {
        parts[blk] = run_block(on, block_task(blk));
        if (holds<BlackBoxKinkError>(parts[blk].error))
          for (std::size_t later = blk + 1; later < nblocks; ++later) stops[later].cancel();
      };
      {
        // The blocks' time is theirs (block_seconds), not a pass of the run's (PassClock).
        const detail::ScopedPassClock paused;
        if (options.block_runner) {
          // Elsewhere (block_tasks.h): every task as bytes, the pieces back in the same order.
          std::vector<std::string> tasks;
          for (const std::size_t blk : order) tasks.push_back(write_task(block_task(blk)));
          for (const std::string& t : tasks) out.report.task_bytes += t.size();
          const std::vector<std::string> pieces = options.block_runner(tasks);
          if (pieces.size() != order.size())
            throw InvalidInputError("adaptive: the block runner returned " + std::to_string(pieces.size()) +
                                     " pieces for " + std::to_string(order.size()) + " tasks");
          for (std::size_t i = 0; i < order.size(); ++i) {
            out.report.piece_bytes += pieces[i].size();
            BlockPart part = read_part(pieces[i]);
            const std::size_t blk = order[i];
            // The piece answers this task, and its seams are the task's (a runner that mixed them up
            // is an error, never a mesh read out of bounds).
            bool fits = part.block == blk;
            if (fits && !part.error) {
              fits = part.ids.size() == cycles[blk].size();
              for (std::size_t c = 0; fits && c < part.ids.size(); ++c) fits = part.ids[c].size() == cycles[blk][c].size();
            }
            if (!fits)
              throw InvalidInputError("adaptive: the block runner returned, for block " + std::to_string(blk) +
                                      ", a piece of another task");
            parts[blk] = std::move(part);
          }
          out.report.threads = 1;
        } else if (field.costly_calls()) {
          // The blocks' evaluations gathered, their trackers on this thread between them
          // (lockstep.h); run_block keeps its errors.
          out.report.threads = 1;
          const LockstepReport lockstep = run_in_lockstep(
              field, order.size(), [&](const Field& on, std::size_t i) { run_here(on, order[i]); });
          out.report.lockstep_tasks = std::max(out.report.lockstep_tasks, lockstep.carriers);
          out.report.lockstep_batches += lockstep.batches;
        } else {
          out.report.threads =
              field.thread_safe() ? std::min<unsigned>(detail::worker_count(options.threads),
                                                       static_cast<unsigned>(std::max<std::size_t>(order.size(), 1)))
                                  : 1;
          detail::parallel_blocks(order.size(), 1, out.report.threads, [&](std::size_t begin, std::size_t end, unsigned) {
            for (std::size_t i = begin; i < end; ++i) run_here(field, order[i]);
          });
        }
      }
      // The blocks up to the lowest one that met a black box's kink ran to their end, the same on
      // every run; those after it may have been stopped anywhere (`stops`) and count for nothing.
      std::size_t kinked = nblocks;
      for (std::size_t blk = 0; blk < nblocks && kinked == nblocks; ++blk)
        if (holds<BlackBoxKinkError>(parts[blk].error)) kinked = blk;
      const std::size_t counted = std::min(nblocks, kinked + 1);
      // Every counted block's tightest bend, whether its mesh is kept or not (a kink's place among them).
      for (std::size_t blk = 0; blk < counted; ++blk)
        if (parts[blk].tightest.first < out.tightest.first) out.tightest = parts[blk].tightest;
      // Whatever the others threw: a cancellation wins, then a black box's kink (no fallback would
      // get past it: the run ends, its tightest bend the kink's), then the first failing block in
      // block order (not in time), so that the outcome is the same on any thread count.
      for (std::size_t blk = 0; blk < counted; ++blk)
        if (holds<CancelledError>(parts[blk].error)) std::rethrow_exception(parts[blk].error);
      if (kinked < nblocks) {
        settings.cancel.check("adaptive");  // the caller's cancel, in a block after the kink, wins too
        for (std::size_t blk = kinked + 1; blk < nblocks; ++blk) out.stopped += holds<CancelledError>(parts[blk].error);
        out.kink = parts[kinked].error;
        std::rethrow_exception(out.kink);
      }
      for (const BlockPart& part : parts)
        if (part.error) std::rethrow_exception(part.error);

      // One mesh, in block order: the seam vertices, then each block's own (room made at once: the
      // torus at factor 40 spent a tenth of its assembly copying arrays as they grew).
      const std::size_t ns = sv.points.size();
      CreaseMesh cm = start_shared(sv.points);
      const Mesh& mesh = cm.mesh;
      {
        std::size_t vertices = ns, triangles = 0;
        for (const BlockPart& part : parts) vertices += part.mesh.positions.size(), triangles += part.mesh.triangles.size();
        cm.mesh.positions.reserve(vertices), cm.mesh.normals.reserve(vertices), cm.mesh.triangles.reserve(triangles);
        cm.target.reserve(vertices), cm.mac.reserve(vertices), cm.shape_index.reserve(vertices);
      }
      out.report.block_seconds.assign(nblocks, 0.0);
      for (std::size_t blk = 0; blk < nblocks; ++blk) {
        BlockPart& part = parts[blk];
        out.report.block_seconds[blk] = part.seconds;
        if (part.mesh.positions.empty()) continue;
        ++out.report.meshed_blocks;
        if (part.forced_closures > 0)
          throw CreaseLayoutError("adaptive: a block's front had to be closed without its tests");
        const std::size_t first_own = mesh.positions.size();
        add_part(cm, part.mesh, part.ids, cycles[blk], part.target, part.mac, part.shape_index);
        const auto [lo, hi] = block_box(blk);
        out.own.push_back({first_own, mesh.positions.size(), lo, hi});
        cm.steps += part.steps;
        cm.splits += part.splits;
        cm.merges += part.merges;
        cm.patch_refusals += part.patch_refusals;
        add_repair_counts(out.quality, part.quality);
        add_tracker_counts(out.tracker, part.tracker);
        out.critical_starts.insert(out.critical_starts.end(), part.critical_starts.begin(), part.critical_starts.end());
        part = BlockPart{};  // copied: freed as the assembly goes
      }
      // Each block's tracker keeps the bounds on its own; the whole mesh keeps max_triangles too.
      if (settings.max_triangles > 0 && mesh.triangles.size() > settings.max_triangles)
        throw LimitExceededError("adaptive: the blocks made " + std::to_string(mesh.triangles.size()) +
                                 " triangles, over max_triangles " + std::to_string(settings.max_triangles));
      finish_shared(cm, ns, "a seam vertex no block reached");
      cm.crease_vertices = 0;  // seam vertices are ordinary surface points: the repair may move them
      // Components by shared vertices (the checks after the repair find any that meet at a vertex
      // alone): a pass over the triangles, where analyze_topology's edge sort was a second serial
      // pass over the mesh, as long as a sixth of the blocks' own time on two threads.
      UnionFind joined(mesh.positions.size());
      std::vector<char> used(mesh.positions.size(), 0);
      for (const auto& t : mesh.triangles) {
        joined.unite(t[0], t[1]);
        joined.unite(t[0], t[2]);
        for (const int v : t) used[static_cast<std::size_t>(v)] = 1;
      }
      for (std::size_t v = 0; v < mesh.positions.size(); ++v)
        out.components += used[v] && joined.find(static_cast<int>(v)) == static_cast<int>(v);
      out.vertices = cm.mesh.positions.size();
      out.mesh = std::move(cm);
    } catch (const GrazedEdgeError& e) {
      grazed = e.what();
      if (layout + 1 < kLayoutShifts.size()) {
        // Afresh, but for the calls the layouts made.
        const std::uint64_t batches = out.report.lockstep_batches;
        out = BlockMeshing{};
        out.report.estimated_triangles = seeds.estimated_triangles;
        out.report.blocks = n;
        out.report.lockstep_batches = batches;
        continue;
      }
      out.report.fallback = e.what();
    } catch (const CreaseLayoutError& e) {
      out.report.fallback = e.what();
    } catch (const BlackBoxKinkError& e) {
      out.report.fallback = e.what();
    } catch (const LimitExceededError& e) {  // a stalled front among them
      out.report.fallback = e.what();
    } catch (const NoSurfaceError& e) {
      out.report.fallback = e.what();
    } catch (const std::logic_error& e) {  // a tracker's own invariant, broken by a block's loops
      out.report.fallback = std::string("adaptive: a block's tracker failed: ") + e.what();
    }
    break;
  }
  out.report.seconds = seconds_since(start);
  return out;
}

// F at the grid's columns in the plane is the mean of the layer's two nodes, its gradient their
// difference across and central differences along the plane (one-sided at the box's sides); the
// columns within kPredictedBand of a cell of the surface count.
double predicted_lean(const SeedGrid& grid, const Box& box, int a, int layer) {
  const int b = (a + 1) % 3, d = (a + 2) % 3;
  const auto in_box = [&](int axis, int i) {
    const double x = grid.origin[axis] + grid.h * i;
    return x >= box.min[axis] && x <= box.max[axis];
  };
  const auto nodes = [&](int i, int j) {  // F at column (i, j) on either side of the plane
    std::array<int, 3> lo{}, hi{};
    lo[a] = layer, hi[a] = layer + 1;
    lo[b] = hi[b] = i;
    lo[d] = hi[d] = j;
    return std::pair{grid.value(lo[0], lo[1], lo[2]), grid.value(hi[0], hi[1], hi[2])};
  };
  const auto mean = [&](int i, int j) {
    const auto [f0, f1] = nodes(i, j);
    return 0.5 * (f0 + f1);
  };
  double lean = 1;
  for (int j = 0; j <= grid.n[d]; ++j) {
    if (!in_box(d, j)) continue;
    for (int i = 0; i <= grid.n[b]; ++i) {
      if (!in_box(b, i)) continue;
      const auto [f0, f1] = nodes(i, j);
      const double f = 0.5 * (f0 + f1);
      const int i0 = i > 0 && in_box(b, i - 1) ? i - 1 : i, i1 = i < grid.n[b] && in_box(b, i + 1) ? i + 1 : i;
      const int j0 = j > 0 && in_box(d, j - 1) ? j - 1 : j, j1 = j < grid.n[d] && in_box(d, j + 1) ? j + 1 : j;
      const double gb = i1 > i0 ? (mean(i1, j) - mean(i0, j)) / (grid.h * (i1 - i0)) : 0.0;
      const double gd = j1 > j0 ? (mean(i, j1) - mean(i, j0)) / (grid.h * (j1 - j0)) : 0.0;
      const double in_plane = std::hypot(gb, gd), gn = std::hypot(in_plane, (f1 - f0) / grid.h);
      if (!std::isfinite(f) || !std::isfinite(gn) || !(gn > 0) || std::abs(f) > kPredictedBand * grid.h * gn) continue;
      lean = std::min(lean, in_plane / gn);
    }
  }
  return lean;
}

bool worth_cutting(const Field& field, const SeedGridStage& seeds) {
  const std::array<int, 3> n = block_counts(field, field.costly_calls(), seeds);
  return n[0] * n[1] * n[2] >= 2;
}

bool uses_blocks(const AdaptiveOptions& options) {
  if (options.blocks) return *options.blocks;
  // A caller's max_steps or max_search_visits bound one tracker's work: tracked alone, unless
  // blocks were asked for (then the run says why it tracked alone, blocks.fallback).
  return options.max_steps == 0 && options.max_search_visits == 0;
}

std::vector<char> sealed_triangles(const BlockMeshing& blocks, const Mesh& mesh) {
  std::vector<char> sealed(mesh.triangles.size(), 0);
  if (blocks.own.empty()) return sealed;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    const auto v = static_cast<std::size_t>(t[0]);
    // The block whose own vertices hold t[0] (the ranges ascend), then the other two corners.
    const auto it = std::upper_bound(blocks.own.begin(), blocks.own.end(), v,
                                     [](std::size_t x, const BlockMeshing::Own& o) { return x < o.end; });
    if (it == blocks.own.end() || v < it->begin) continue;
    bool own = true;
    Vec3 lo = mesh.positions[v], hi = lo;
    for (int k = 1; k < 3; ++k) {
      const auto w = static_cast<std::size_t>(t[k]);
      own = own && w >= it->begin && w < it->end;
      if (!own) break;
      lo = lo.cwiseMin(mesh.positions[w]);
      hi = hi.cwiseMax(mesh.positions[w]);
    }
    sealed[i] = own && (lo.array() > it->lo.array()).all() && (hi.array() < it->hi.array()).all();
  }
  return sealed;
}

}  // namespace cdp::adaptive
