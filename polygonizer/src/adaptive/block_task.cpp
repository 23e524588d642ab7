#include "block_task.h"

#include "crease_patches.h"
#include "repair_context.h"

#include <cdp/core/block_tasks.h>
#include <cdp/core/cancel.h>
#include <cdp/core/curvature.h>
#include <cdp/core/triangle_intersection.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace cdp::adaptive {

namespace {

using Clock = std::chrono::steady_clock;

// The margin of a block's point and patch tests, as a share of the step or edge length: a point
// on a seam lies on the block's wall to rounding, and a chord between two seam vertices of one
// wall lies in it.
constexpr double kOutsideBlock = 0.1;

// Repairs a block's mesh with its seams kept (quality.h), then renumbers what the part keeps per
// vertex: the seams' ids, the targets, and with curvature properties the curvature, measured
// again where the repair moved or added a vertex.
void repair_block(const Field& field, const Settings& settings, QualityOptions qo, BlockPart& part) {
  qo.keep_boundary = true;
  qo.count_near_boundary = false;
  qo.threads = 1;  // the blocks are the parallel part
  // The aim is the whole mesh's mean, which no block knows: repair_mesh searches the whole mesh
  // where that is over it.
  qo.aim_mean_edge_ratio = 0;
  const std::vector<Vec3> before = part.mesh.positions;
  std::vector<int> renumbered;
  part.quality = improve_mesh(field, part.mesh, qo, &renumbered);
  for (auto& ids : part.ids)
    for (int& v : ids) {
      v = renumbered[static_cast<std::size_t>(v)];
      if (v < 0) throw std::logic_error("adaptive: a block's repair removed a seam vertex");
    }
  const std::size_t n = part.mesh.positions.size();
  std::vector<double> target(n), mac(n), shape(n);
  std::vector<char> kept(n, 0), moved(n, 0);  // from an input vertex; and moved by the repair
  for (std::size_t v = 0; v < renumbered.size(); ++v) {
    if (renumbered[v] < 0) continue;
    const auto r = static_cast<std::size_t>(renumbered[v]);
    kept[r] = 1;
    target[r] = part.target[v];
    mac[r] = part.mac[v];
    shape[r] = part.shape_index[v];
    moved[r] = part.mesh.positions[r] != before[v];
  }
  // A vertex the repair added takes the smallest target of the input vertices around it (the
  // seeding's fronts may meet it; the blocks' own are done).
  for (std::size_t v = 0; v < n; ++v)
    if (!kept[v]) target[v] = std::numeric_limits<double>::infinity();
  for (const auto& t : part.mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(t[k]);
      if (kept[v]) continue;
      for (int j = 1; j < 3; ++j) {
        const auto w = static_cast<std::size_t>(t[(k + j) % 3]);
        if (kept[w]) target[v] = std::min(target[v], target[w]);
      }
    }
  // One added among added ones only (a refinement's splits of splits): the part's smallest.
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < n; ++v)
    if (kept[v]) smallest = std::min(smallest, target[v]);
  for (std::size_t v = 0; v < n; ++v)
    if (!kept[v] && !std::isfinite(target[v])) target[v] = smallest;
  // The curvature only where the caller asked for it (a Hessian a vertex: on the bunny VIS-800
  // at factor 5, a tenth of the blocks' time).
  if (settings.curvature_properties) {
    std::vector<std::size_t> which;
    std::vector<Vec3> at;
    for (std::size_t v = 0; v < n; ++v)
      if (!kept[v] || moved[v]) which.push_back(v), at.push_back(part.mesh.positions[v]);
    const std::vector<Curvature> c = curvatures_at(field, at);
    for (std::size_t i = 0; i < which.size(); ++i) mac[which[i]] = c[i].mac, shape[which[i]] = c[i].shape_index;
  }
  part.target = std::move(target);
  part.mac = std::move(mac);
  part.shape_index = std::move(shape);
}

}  // namespace

BlockPart run_block(const Field& field, const BlockTask& task) {
  BlockPart part;
  part.block = task.block;
  try {
    const auto t0 = Clock::now();
    const Vec3 lo = task.lo, hi = task.hi;
    const auto within = [lo, hi](const Vec3& x, double margin) {
      return (x.array() >= lo.array() - margin).all() && (x.array() <= hi.array() + margin).all();
    };
    Tracker tracker(field, task.settings, part.mesh);
    // Its counters and tightest bend, whatever it throws (a kink of a black box ends the run).
    struct Keep {
      const Tracker& tracker;
      BlockPart& part;
      ~Keep() { part.tracker = tracker.report(), part.tightest = tracker.tightest_bend(); }
    } keep{tracker, part};
    if (task.estimated_area > 0) tracker.set_estimated_area(task.estimated_area);
    tracker.set_patch_test([&field, within](const Vec3& a, const Vec3& b) {
      Vec3 m = 0.5 * (a + b);
      for (int it = 0; it < 3; ++it) {
        Vec3 g;
        const double v = field.value_gradient(m, g);
        if (!(g.squaredNorm() > 0)) return false;
        m -= v / g.squaredNorm() * g;
      }
      return within(m, kOutsideBlock * (a - b).norm());
    });
    tracker.set_point_test([within](const Vec3& x, double step) { return within(x, kOutsideBlock * step); });
    part.ids = tracker.mesh_from_loops(task.loops);
    part.target = tracker.vertex_edge_length();
    part.mac = tracker.vertex_mac();
    part.shape_index = tracker.vertex_shape_index();
    part.steps = tracker.steps();
    part.splits = tracker.splits();
    part.merges = tracker.merges();
    part.forced_closures = tracker.forced_closures();
    part.patch_refusals = tracker.patch_refusals();
    part.critical_starts = tracker.critical_starts();
    if (task.repair) repair_block(field, task.settings, *task.repair, part);
    if (task.check_self_intersections &&
        !self_intersecting_pairs(part.mesh, 1, 1, &task.settings.cancel).empty())
      throw NoSurfaceError("adaptive: a block's mesh intersects itself");
    part.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  } catch (...) {
    part.error = std::current_exception();
  }
  return part;
}

// The bytes: this build's memory layout of each number, in the order written, after a tag that
// names the format and the byte order (client and workers run one build; a tag that differs is
// refused rather than misread). Arrays are a count and then their elements as they lie in memory,
// so a piece of 10^5 triangles costs a copy. The core depends on Eigen only (README), so no
// serialization library: the format is private to one build and never stored.
namespace {

constexpr std::uint64_t kTaskTag = 0x31'6b'73'61'74'70'64'63;  // "cdptask1"
constexpr std::uint64_t kPartTag = 0x32'74'72'61'70'70'64'63;  // "cdppart2"

// Every struct written field by field below; a field added to one of them changes its size on
// this platform, and this reminds whoever adds it to write it too (a field left out would be
// the worker's default: another mesh than the one-process run's, silently).
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(Sizing) == 48 && sizeof(FinerZone) == 40 && sizeof(Settings) == 200,
              "a field added to Settings: write and read it in block_task.cpp");
static_assert(sizeof(QualityOptions) == 104, "a field added to QualityOptions: write and read it in block_task.cpp");
static_assert(sizeof(QualityReport) == 184, "a field added to QualityReport: write and read it in block_task.cpp");
static_assert(sizeof(TrackerReport) == 112, "a field added to TrackerReport: write and read it in block_task.cpp");
static_assert(sizeof(Tracker::Placed) == 264 && sizeof(Curvature) == 200 && sizeof(CriticalStart) == 56,
              "a field added to Tracker::Placed or CriticalStart: write and read it in block_task.cpp");
#endif

// Bytes a Placed and a CriticalStart take when written (Reader::count's least sizes).
constexpr std::size_t kPlacedBytes = 24 + (24 + 72 + 16 + 48 + 40) + 1 + 24 + 8;
constexpr std::size_t kCriticalStartBytes = 24 + 24 + 8;
constexpr TriangleCountRule kLastRule = TriangleCountRule::Hartmann;

[[noreturn]] void bad_piece(const std::string& what) {
  throw InvalidInputError("adaptive: a block piece whose " + what);
}

// A piece's numbers agree with each other: every index names one of its vertices, and every
// per-vertex array has one entry a vertex (a piece from another build, or a runner's mix-up,
// is refused here rather than read out of bounds).
void check_part(const BlockPart& part) {
  const Mesh& m = part.mesh;
  const std::size_t n = m.positions.size();
  if (m.normals.size() != n || part.target.size() != n || part.mac.size() != n || part.shape_index.size() != n)
    bad_piece("per-vertex arrays do not match its vertices");
  if (!m.corner_normals.empty() && m.corner_normals.size() != m.triangles.size())
    bad_piece("corner normals do not match its triangles");
  for (const auto& [name, values] : m.vertex_scalars)
    if (values.size() != n) bad_piece("vertex scalars " + name + " do not match its vertices");
  const auto in_range = [n](int v) { return v >= 0 && static_cast<std::size_t>(v) < n; };
  for (const auto& t : m.triangles)
    if (!in_range(t[0]) || !in_range(t[1]) || !in_range(t[2])) bad_piece("triangles name vertices it lacks");
  for (const auto& ids : part.ids)
    for (const int v : ids)
      if (!in_range(v)) bad_piece("seam ids name vertices it lacks");
}

class Writer {
 public:
  explicit Writer(std::uint64_t tag) { num(tag); }
  template <class T>
  void num(T x) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>);
    if constexpr (std::is_same_v<T, bool>) {
      const std::uint8_t b = x ? 1 : 0;
      bytes(&b, 1);
    } else {
      bytes(&x, sizeof x);
    }
  }
  void vec(const Vec3& v) { bytes(v.data(), 3 * sizeof(double)); }
  void mat(const Mat3& m) { bytes(m.data(), 9 * sizeof(double)); }
  template <class T>
  void array(const std::vector<T>& v) {
    num<std::uint64_t>(v.size());
    if constexpr (std::is_arithmetic_v<T>) {
      bytes(v.data(), v.size() * sizeof(T));
    } else if constexpr (std::is_same_v<T, Vec3>) {
      static_assert(sizeof(Vec3) == 3 * sizeof(double));
      bytes(v.data(), v.size() * sizeof(Vec3));
    } else {
      static_assert(sizeof(T) % sizeof(typename T::value_type) == 0 && std::is_arithmetic_v<typename T::value_type>);
      bytes(v.data(), v.size() * sizeof(T));  // std::array of numbers
    }
  }
  std::string take() { return std::move(out_); }

 private:
  void bytes(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string out_;
};

class Reader {
 public:
  Reader(std::string_view in, std::uint64_t tag, const char* what) : in_(in), what_(what) {
    if (num<std::uint64_t>() != tag)
      throw InvalidInputError(std::string("adaptive: not a block ") + what_ + " of this build of the library");
  }
  template <class T>
  T num() {
    T x;
    bytes(&x, sizeof x);
    return x;
  }
  Vec3 vec() {
    Vec3 v;
    bytes(v.data(), 3 * sizeof(double));
    return v;
  }
  Mat3 mat() {
    Mat3 m;
    bytes(m.data(), 9 * sizeof(double));
    return m;
  }
  template <class T>
  std::vector<T> array() {
    const auto n = num<std::uint64_t>();
    if (n > (in_.size() - at_) / sizeof(T)) truncated();
    std::vector<T> v(static_cast<std::size_t>(n));
    bytes(v.data(), v.size() * sizeof(T));
    return v;
  }
  // The length of a list read element by element, each at least `least` bytes of the input, so
  // that a count the bytes cannot hold is refused before anything is allocated for it.
  std::size_t count(std::size_t least) {
    const auto n = num<std::uint64_t>();
    if (n > (in_.size() - at_) / least) truncated();
    return static_cast<std::size_t>(n);
  }
  // A bool as written (one byte, 0 or 1), an enum up to its last value.
  bool flag() {
    const auto b = num<std::uint8_t>();
    if (b > 1) truncated();
    return b == 1;
  }
  template <class E>
  E choice(E last) {
    using U = std::underlying_type_t<E>;
    const auto v = num<U>();
    bool below = false;
    if constexpr (std::is_signed_v<U>) below = v < 0;
    if (below || v > static_cast<U>(last)) truncated();
    return static_cast<E>(v);
  }
  void end() const {
    if (at_ != in_.size()) truncated();
  }

 private:
  void bytes(void* p, std::size_t n) {
    if (n > in_.size() - at_) truncated();
    if (n > 0) std::memcpy(p, in_.data() + at_, n);
    at_ += n;
  }
  [[noreturn]] void truncated() const {
    throw InvalidInputError(std::string("adaptive: a block ") + what_ + " cut short or from another build");
  }
  std::string_view in_;
  std::size_t at_ = 0;
  const char* what_;
};

void write_settings(Writer& w, const Settings& s) {
  w.num(s.sizing.mode), w.num(s.sizing.factor), w.num(s.sizing.tolerance), w.num(s.sizing.min_edge);
  w.num(s.sizing.max_edge), w.num(s.sizing.max_turn);
  w.num(s.rule), w.num(s.collision_factor), w.num(s.max_triangles), w.num(s.max_steps);
  w.num(s.search_visits_per_step), w.num(s.callers_search_bound), w.num(s.stop_at_kink), w.num(s.curvature_properties);
  w.num(s.grading), w.num(s.side_points), w.num(s.diagonal), w.num(s.rollback), w.num(s.anticipate);
  w.num<std::uint64_t>(s.finer_zones.size());
  for (const FinerZone& z : s.finer_zones) w.vec(z.center), w.num(z.radius), w.num(z.edge);
  w.num(s.look_ahead), w.num(s.look_ahead_gradation), w.num(s.hash_cell);
}

Settings read_settings(Reader& r, const CancelToken& cancel) {
  Settings s;
  s.sizing.mode = r.choice(SizingMode::Chord), s.sizing.factor = r.num<double>(), s.sizing.tolerance = r.num<double>();
  s.sizing.min_edge = r.num<double>(), s.sizing.max_edge = r.num<double>(), s.sizing.max_turn = r.num<double>();
  s.rule = r.choice(kLastRule), s.collision_factor = r.num<double>();
  s.max_triangles = r.num<std::size_t>(), s.max_steps = r.num<std::size_t>();
  s.search_visits_per_step = r.num<std::uint64_t>(), s.callers_search_bound = r.flag(), s.stop_at_kink = r.flag();
  s.curvature_properties = r.flag(), s.grading = r.flag(), s.side_points = r.flag();
  s.diagonal = r.num<double>(), s.rollback = r.flag(), s.anticipate = r.flag();
  s.finer_zones.resize(r.count(5 * sizeof(double)));
  for (FinerZone& z : s.finer_zones) z.center = r.vec(), z.radius = r.num<double>(), z.edge = r.num<double>();
  s.look_ahead = r.flag(), s.look_ahead_gradation = r.num<double>(), s.hash_cell = r.num<double>();
  s.cancel = cancel;
  return s;
}

void write_quality_options(Writer& w, const QualityOptions& q) {
  w.num(q.improve_below), w.num(q.tolerance), w.num(q.diagonal), w.num(q.min_edge), w.num(q.last_resort_min_edge);
  w.num(q.measure_near_bound), w.num(q.aim_mean_edge_ratio), w.num(q.threads), w.num(q.keep_boundary);
  w.num(q.count_near_boundary), w.num(q.predict_estimates);
}

QualityOptions read_quality_options(Reader& r, const CancelToken& cancel) {
  QualityOptions q;
  q.improve_below = r.num<double>(), q.tolerance = r.num<double>(), q.diagonal = r.num<double>();
  q.min_edge = r.num<double>(), q.last_resort_min_edge = r.num<double>(), q.measure_near_bound = r.flag();
  q.aim_mean_edge_ratio = r.num<double>(), q.threads = r.num<int>(), q.keep_boundary = r.flag();
  q.count_near_boundary = r.flag(), q.predict_estimates = r.choice(QualityOptions::Predict::Always);
  q.cancel = cancel;
  return q;
}

// QualityReport: its counts in declaration order.
template <class Q, class F>
void quality_counts(Q& q, F&& f) {
  f(q.bad_before), f(q.bad_after), f(q.flips), f(q.moves), f(q.collapses), f(q.relaxed), f(q.relax_flips);
  f(q.relax_searched), f(q.relax_search_sweeps), f(q.relax_crossings), f(q.splits), f(q.inserts);
  f(q.last_resorts), f(q.crease_vertices), f(q.measured_densely), f(q.refine_measured), f(q.refine_cleared);
  f(q.over_tolerance);
}

// TrackerReport: every number in declaration order (min_curvature_radius too).
template <class R, class F>
void tracker_counts(R& t, F&& f) {
  f(t.steps), f(t.search_visits), f(t.deferrals), f(t.anticipations), f(t.side_points), f(t.forced_closures);
  f(t.rollbacks), f(t.rollbacks_failed), f(t.crease_points), f(t.over_mesh_rejections), f(t.sheet_jumps);
  f(t.curvature_seconds), f(t.hessian_seconds), f(t.min_curvature_radius);
}

// What a block's run threw, travelling in its piece: a tracker's failure by its kind (the run
// falls back to tracking alone; a black box's kink ends it), Other for any other error (the
// field's: a Python function's), raised by the run as a std::runtime_error with its message, in
// block order as its own blocks'.
enum class Failure : std::uint8_t { None, Layout, Stalled, Limit, NoSurface, Logic, Cancelled, Other, Kink };

}  // namespace

std::string write_task(const BlockTask& task) {
  Writer w(kTaskTag);
  w.num<std::uint64_t>(task.block);
  write_settings(w, task.settings);
  w.num(task.estimated_area), w.vec(task.lo), w.vec(task.hi);
  w.num<std::uint64_t>(task.loops.size());
  for (const auto& loop : task.loops) {
    w.num<std::uint64_t>(loop.size());
    for (const Tracker::Placed& p : loop) {
      const Curvature& c = p.curvature;
      w.vec(p.point), w.vec(c.normal), w.mat(c.C), w.num(c.k1), w.num(c.k2), w.vec(c.dir1), w.vec(c.dir2);
      w.num(c.gaussian), w.num(c.mean), w.num(c.mac), w.num(c.min_radius), w.num(c.shape_index);
      w.num(p.to_critical.has_value());
      w.vec(p.to_critical.value_or(Vec3::Zero()));
      w.num(p.seam_target);
    }
  }
  w.num(task.repair.has_value());
  if (task.repair) write_quality_options(w, *task.repair);
  w.num(task.check_self_intersections);
  return w.take();
}

BlockTask read_task(std::string_view bytes, const CancelToken& cancel) {
  Reader r(bytes, kTaskTag, "task");
  BlockTask task;
  task.block = r.num<std::uint64_t>();
  task.settings = read_settings(r, cancel);
  task.estimated_area = r.num<double>(), task.lo = r.vec(), task.hi = r.vec();
  task.loops.resize(r.count(sizeof(std::uint64_t)));
  for (auto& loop : task.loops) {
    loop.resize(r.count(kPlacedBytes));
    for (Tracker::Placed& p : loop) {
      Curvature& c = p.curvature;
      p.point = r.vec(), c.normal = r.vec(), c.C = r.mat(), c.k1 = r.num<double>(), c.k2 = r.num<double>();
      c.dir1 = r.vec(), c.dir2 = r.vec(), c.gaussian = r.num<double>(), c.mean = r.num<double>();
      c.mac = r.num<double>(), c.min_radius = r.num<double>(), c.shape_index = r.num<double>();
      const bool critical = r.flag();
      const Vec3 step = r.vec();
      if (critical) p.to_critical = step;
      p.seam_target = r.num<double>();
    }
  }
  if (r.flag()) task.repair = read_quality_options(r, cancel);
  task.check_self_intersections = r.flag();
  r.end();
  return task;
}

std::string write_part(const BlockPart& part) {
  Writer w(kPartTag);
  Failure failure = Failure::None;
  std::string message;
  if (part.error) try {
      std::rethrow_exception(part.error);
    } catch (const CancelledError& e) {
      failure = Failure::Cancelled, message = e.what();
    } catch (const CreaseLayoutError& e) {
      failure = Failure::Layout, message = e.what();
    } catch (const StalledFrontError& e) {
      failure = Failure::Stalled, message = e.what();
    } catch (const BlackBoxKinkError& e) {
      failure = Failure::Kink, message = e.what();
    } catch (const LimitExceededError& e) {
      failure = Failure::Limit, message = e.what();
    } catch (const NoSurfaceError& e) {
      failure = Failure::NoSurface, message = e.what();
    } catch (const std::logic_error& e) {
      failure = Failure::Logic, message = e.what();
    } catch (const std::exception& e) {
      failure = Failure::Other, message = e.what();
    } catch (...) {
      failure = Failure::Other, message = "an error that is no std::exception";
    }
  w.num<std::uint64_t>(part.block);
  w.num(failure);
  w.array(std::vector<char>(message.begin(), message.end()));
  w.num(part.tightest.first), w.vec(part.tightest.second);  // a failed block's too (a kink's place)
  if (failure != Failure::None) return w.take();
  const Mesh& m = part.mesh;
  w.array(m.positions), w.array(m.normals), w.array(m.triangles);
  w.num<std::uint64_t>(m.corner_normals.size());
  for (const auto& corners : m.corner_normals)
    for (const Vec3& n : corners) w.vec(n);
  w.num<std::uint64_t>(m.vertex_scalars.size());
  for (const auto& [name, values] : m.vertex_scalars)
    w.array(std::vector<char>(name.begin(), name.end())), w.array(values);
  w.num<std::uint64_t>(part.ids.size());
  for (const auto& ids : part.ids) w.array(ids);
  w.array(part.target), w.array(part.mac), w.array(part.shape_index);
  w.num(part.steps), w.num(part.splits), w.num(part.merges), w.num(part.forced_closures), w.num(part.patch_refusals);
  w.num<std::uint64_t>(part.critical_starts.size());
  for (const CriticalStart& c : part.critical_starts) w.vec(c.point), w.vec(c.step), w.num(c.edge);
  tracker_counts(part.tracker, [&]<class T>(const T& x) { w.num(x); });
  const QualityReport& q = part.quality;
  w.num(q.repair_below_degrees);
  quality_counts(q, [&](std::size_t x) { w.num(x); });
  w.num(q.over_tolerance_worst), w.vec(q.over_tolerance_near);
  w.num(part.seconds);
  return w.take();
}

BlockPart read_part(std::string_view bytes) {
  Reader r(bytes, kPartTag, "piece");
  BlockPart part;
  part.block = r.num<std::uint64_t>();
  const auto failure = r.choice(Failure::Kink);
  const std::vector<char> text = r.array<char>();
  const std::string message(text.begin(), text.end());
  part.tightest.first = r.num<double>(), part.tightest.second = r.vec();
  switch (failure) {
    case Failure::None: break;
    case Failure::Layout: part.error = std::make_exception_ptr(CreaseLayoutError(message)); break;
    case Failure::Stalled: part.error = std::make_exception_ptr(StalledFrontError(message)); break;
    case Failure::Limit: part.error = std::make_exception_ptr(LimitExceededError(message)); break;
    case Failure::NoSurface: part.error = std::make_exception_ptr(NoSurfaceError(message)); break;
    case Failure::Logic: part.error = std::make_exception_ptr(std::logic_error(message)); break;
    case Failure::Cancelled: part.error = std::make_exception_ptr(CancelledError(message)); break;
    case Failure::Other: part.error = std::make_exception_ptr(std::runtime_error(message)); break;
    case Failure::Kink: part.error = std::make_exception_ptr(BlackBoxKinkError(message)); break;
  }
  if (failure != Failure::None) {
    r.end();
    return part;
  }
  Mesh& m = part.mesh;
  m.positions = r.array<Vec3>(), m.normals = r.array<Vec3>(), m.triangles = r.array<std::array<int, 3>>();
  m.corner_normals.resize(r.count(3 * sizeof(Vec3)));
  for (auto& corners : m.corner_normals)
    for (Vec3& n : corners) n = r.vec();
  for (std::size_t k = r.count(2 * sizeof(std::uint64_t)); k > 0; --k) {
    const std::vector<char> name = r.array<char>();
    m.vertex_scalars[std::string(name.begin(), name.end())] = r.array<double>();
  }
  part.ids.resize(r.count(sizeof(std::uint64_t)));
  for (auto& ids : part.ids) ids = r.array<int>();
  part.target = r.array<double>(), part.mac = r.array<double>(), part.shape_index = r.array<double>();
  part.steps = r.num<std::size_t>(), part.splits = r.num<std::size_t>(), part.merges = r.num<std::size_t>();
  part.forced_closures = r.num<std::size_t>(), part.patch_refusals = r.num<std::size_t>();
  part.critical_starts.resize(r.count(kCriticalStartBytes));
  for (CriticalStart& c : part.critical_starts) c.point = r.vec(), c.step = r.vec(), c.edge = r.num<double>();
  tracker_counts(part.tracker, [&]<class T>(T& x) { x = r.num<T>(); });
  QualityReport& q = part.quality;
  q.repair_below_degrees = r.num<double>();
  quality_counts(q, [&](std::size_t& x) { x = r.num<std::size_t>(); });
  q.over_tolerance_worst = r.num<double>(), q.over_tolerance_near = r.vec();
  part.seconds = r.num<double>();
  r.end();
  check_part(part);
  return part;
}

}  // namespace cdp::adaptive

namespace cdp {

std::string run_block_task(const Field& field, std::string_view task) {
  return adaptive::write_part(adaptive::run_block(field, adaptive::read_task(task)));
}

}  // namespace cdp
