// The implicit field interface every algorithm of the project works on.
//
// A field F: R^3 -> R is negative inside, positive outside and zero on the surface, so its
// gradient points outward. Models implement the protected eval_* hooks; callers use the public
// wrappers, which count evaluations by kind so that algorithms can report their cost.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products, used with Vec3 everywhere

#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace cdp {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// Axis-aligned box.
struct Box {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();

  Vec3 size() const { return max - min; }
  Vec3 center() const { return 0.5 * (min + max); }
  double diagonal() const { return size().norm(); }
  bool contains(const Vec3& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  bool valid() const { return (max.array() > min.array()).all() && min.allFinite() && max.allFinite(); }
  Box inflated(double margin) const { return {min.array() - margin, max.array() + margin}; }
};

// Evaluation counts by kind. `value` counts value-only evaluations (single or batched),
// `value_gradient` value-and-gradient evaluations, `gradient_hessian` evaluations that also
// produce the Hessian.
struct EvaluationCounts {
  std::uint64_t value = 0;
  std::uint64_t value_gradient = 0;
  std::uint64_t gradient_hessian = 0;
  std::uint64_t total() const { return value + value_gradient + gradient_hessian; }
  EvaluationCounts operator-(const EvaluationCounts& o) const {
    return {value - o.value, value_gradient - o.value_gradient, gradient_hessian - o.gradient_hessian};
  }
  EvaluationCounts& operator+=(const EvaluationCounts& o) {
    value += o.value;
    value_gradient += o.value_gradient;
    gradient_hessian += o.gradient_hessian;
    return *this;
  }
};

// The evaluations of one field counted by kind from any number of threads, each thread adding
// to its own slot (threads beyond kSlots share them, round robin) and counts() summing the slots:
// with one counter every evaluation of one thread would take the counter's cache line, and the
// field's own data beside it, from the others.
class EvaluationCounter {
 public:
  void add_values(std::uint64_t n) const { slot().value.fetch_add(n, std::memory_order_relaxed); }
  void add_value_gradients(std::uint64_t n) const { slot().value_gradient.fetch_add(n, std::memory_order_relaxed); }
  void add_gradient_hessians(std::uint64_t n) const {
    slot().gradient_hessian.fetch_add(n, std::memory_order_relaxed);
  }
  // Exact while no thread counts; a snapshot of what was counted so far otherwise.
  EvaluationCounts counts() const {
    EvaluationCounts c;
    for (std::size_t i = 0; i < kSlots; ++i) {
      c.value += slots_[i].value.load(std::memory_order_relaxed);
      c.value_gradient += slots_[i].value_gradient.load(std::memory_order_relaxed);
      c.gradient_hessian += slots_[i].gradient_hessian.load(std::memory_order_relaxed);
    }
    return c;
  }
  void reset() const {
    for (std::size_t i = 0; i < kSlots; ++i) {
      slots_[i].value.store(0, std::memory_order_relaxed);
      slots_[i].value_gradient.store(0, std::memory_order_relaxed);
      slots_[i].gradient_hessian.store(0, std::memory_order_relaxed);
    }
  }

 private:
  // As many as the threads a run uses by default (at most 8, --threads).
  static constexpr std::size_t kSlots = 8;
  // A cache line each (64 bytes on the x86-64 and ARM64 machines we build for).
  struct alignas(64) Slot {
    std::atomic<std::uint64_t> value{0}, value_gradient{0}, gradient_hessian{0};
  };
  static std::size_t thread_slot() {
    static std::atomic<std::size_t> next{0};
    thread_local const std::size_t mine = next.fetch_add(1, std::memory_order_relaxed) % kSlots;
    return mine;
  }
  Slot& slot() const { return slots_[thread_slot()]; }
  // On the heap: a field's members stay off these lines, and Field itself is not over-aligned.
  std::unique_ptr<Slot[]> slots_ = std::make_unique<Slot[]>(kSlots);
};

// One smooth piece of a field built with min, max or abs (a CSG shape): which argument the
// model takes at each of its branch points, and the piece's value, gradient and Hessian at a
// point. Creases of the surface lie where two pieces are zero, corners where three are.
struct FieldPiece {
  std::vector<std::uint8_t> branch;  // the model's own encoding: give it back to Field::piece
  double value = 0;
  Vec3 gradient = Vec3::Zero();
  Mat3 hessian = Mat3::Zero();
};

// Pieces whose unit gradients at one point agree to this cosine are the same piece: creases this
// project meshes have dihedral angles far above the 2.6 degrees it allows (crease tracing and
// crease-aware meshing compare pieces so, since one piece may carry several branch codes; a
// branch point whose two branches agree so where they switch is no crease, Field::pieces).
inline constexpr double kSamePieceCosine = 0.999;

// Evaluations that differ in their last bits only: value and gradient within kSameToRounding of
// the reference's size (1 + |value| + |gradient|). Two pieces equal so at a point are one
// function there. A choice hidden behind a blend changes the field in its last bits only: a
// smooth difference d0 - (d1 + d0) h at h = 1 leaves d0 in the sum, so each side of d0's max
// gives other roundings. (Bit for bit, the choice of the box's max in a box with two crossing
// holes cut smoothly was fixed in the pieces of one tunnel's wall at some points and free at
// others: two codes for one piece, whose patch boundaries crossed.) Used by Field::pieces (a
// hidden choice is free), the crease tracer (a crease that fades into a seam) and crease-aware
// meshing (pieces of one function, cycles of one region).
inline constexpr double kSameToRounding = 1e-12;
// \return whether `value` and `gradient` are each within kSameToRounding (1 + |reference_value| +
//         |reference_gradient|) of the reference's.
inline bool same_to_rounding(double reference_value, const Eigen::Vector3d& reference_gradient, double value,
                             const Eigen::Vector3d& gradient) {
  const double scale = kSameToRounding * (1 + std::abs(reference_value) + reference_gradient.norm());
  return std::abs(value - reference_value) <= scale && (gradient - reference_gradient).norm() <= scale;
}

class Field {
  // F - c stands for F and passes every hook on to it (models/level_shift.h).
  friend class LevelShift;

 public:
  virtual ~Field() = default;
  Field() = default;
  Field(const Field&) = delete;
  Field& operator=(const Field&) = delete;

  // \return F(p).
  // \throw what the model's evaluation throws, unchanged (a Python field: InvalidInputError for a
  //        result of the wrong shape, or the function's own error); the built-in models throw none.
  double value(const Vec3& p) const {
    counter_.add_values(1);
    return eval_value(p);
  }
  // Value and gradient in one evaluation; returns the value.
  // \throw as value().
  double value_gradient(const Vec3& p, Vec3& gradient) const {
    counter_.add_value_gradients(1);
    return eval_value_gradient(p, gradient);
  }
  // \return the gradient of F at p (one value_gradient evaluation).
  // \throw as value().
  Vec3 gradient(const Vec3& p) const {
    Vec3 g;
    value_gradient(p, g);
    return g;
  }
  // Value, gradient and Hessian in one evaluation; returns the value.
  // \throw as value().
  double gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
    counter_.add_gradient_hessians(1);
    return eval_gradient_hessian(p, gradient, hessian);
  }
  // Batched values: out[i] = F(points[i]). Models with a vectorized kernel override eval_values.
  // \pre points and out hold n elements each.
  // \throw as value().
  void values(const Vec3* points, double* out, std::size_t n) const {
    counter_.add_values(n);
    eval_values(points, out, n);
  }
  // Values on a cubic lattice of n^3 points: out[(c * n + b) * n + a] = F(origin + step * (a, b,
  // c)), the same numbers as values() at those points. Counted as n^3 value evaluations. Sampled
  // volumes evaluate a lattice separably, an axis at a time, many times faster than point by point.
  // \pre n >= 1 and out holds n^3 elements.
  // \throw as value().
  void values_on_lattice(const Vec3& origin, double step, int n, double* out) const {
    counter_.add_values(static_cast<std::size_t>(n) * n * n);
    eval_values_on_lattice(origin, step, n, out);
  }
  // Batched value_gradient: values[i] and gradients[i] at points[i]. Counted as n value_gradient
  // evaluations, as n single calls would be, so that statistics measure the work, not the calls.
  // \pre points, values and gradients hold n elements each.
  // \throw as value().
  void values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const {
    counter_.add_value_gradients(n);
    eval_values_gradients(points, values, gradients, n);
  }
  // Batched gradient_hessian, counted as n gradient_hessian evaluations.
  // \pre points, values, gradients and hessians hold n elements each.
  // \throw as value().
  void gradients_hessians(const Vec3* points, double* values, Vec3* gradients, Mat3* hessians, std::size_t n) const {
    counter_.add_gradient_hessians(n);
    eval_gradients_hessians(points, values, gradients, hessians, n);
  }

  // One batch of points and where their evaluations go, for evaluate_together: `gradients` for
  // values with gradients and Hessians, `hessians` for those with Hessians.
  struct Batch {
    const Vec3* points = nullptr;
    double* values = nullptr;
    Vec3* gradients = nullptr;
    Mat3* hessians = nullptr;
    std::size_t n = 0;
  };
  // values(plain), values_gradients(with_gradients) and gradients_hessians(with_hessians) in one
  // evaluation where the model can (each batch may be empty): the same numbers, counted as those
  // three would count them. A field whose calls cost more than their points (costly_calls: a Python
  // function without derivatives of its own) makes one call for all three batches' points where
  // three calls would cost three trips into the interpreter; tasks in lockstep ask for every kind
  // together (adaptive/lockstep.h).
  // \pre each batch's arrays hold its n elements (plain needs no gradients, with_gradients no
  //      Hessians).
  // \throw as value().
  void evaluate_together(const Batch& plain, const Batch& with_gradients, const Batch& with_hessians) const {
    counter_.add_values(plain.n);
    counter_.add_value_gradients(with_gradients.n);
    counter_.add_gradient_hessians(with_hessians.n);
    eval_together(plain, with_gradients, with_hessians);
  }

  // The smooth pieces of the field near p: one per choice of branches of its min, max and abs
  // that is taken somewhere within `radius` of p (to first order: a branch point counts when
  // the surface where its two arguments are equal lies within `radius`), each evaluated at p,
  // distinct pieces only, the branches as taken at p first. Branch points without a crease
  // (BranchKind::Smooth) are never split: they are kFreeBranch in every piece. One piece where
  // the field is smooth within `radius`; none from a model that does not report its pieces
  // (then it is treated as smooth everywhere). Counted as one value_gradient and one
  // gradient_hessian per piece.
  // \return the pieces, the branches as taken at p first; empty where the model reports no branch
  //         point at p (always, for a model without branch points).
  // \throw as value() (a first call also classifies the branch points: branch_kinds).
  std::vector<FieldPiece> pieces(const Vec3& p, double radius) const {
    counter_.add_value_gradients(1);
    std::vector<FieldPiece> out = eval_pieces(p, radius, true);
    counter_.add_gradient_hessians(out.size());
    return out;
  }
  // pieces() without their Hessians (left zero), for callers that compare normals only (crease
  // tracing): the same values and gradients bit for bit, each piece evaluated to first order
  // (no second derivatives carried through the formula). Pieces with the same value and gradient at p are one here
  // (pieces() also compares their Hessians, which tells them apart only where two pieces touch
  // to first order at p itself). Counted as one value_gradient, and one more per piece.
  // \return as pieces().
  // \throw as pieces().
  std::vector<FieldPiece> pieces_first_order(const Vec3& p, double radius) const {
    counter_.add_value_gradients(1);
    std::vector<FieldPiece> out = eval_pieces(p, radius, false);
    counter_.add_value_gradients(out.size());
    return out;
  }
  // Whether the model has creases: a branch point (min, max, abs) of kind Creased
  // (branch_kinds), seen switching on the surface with different normals on its two sides. The
  // first call classifies the branch points. A crease found nowhere on that grid (a feature
  // smaller than its cells) is missed, as the crease tracer's grid would miss it.
  // \throw as value() (on the first call, which evaluates the field).
  bool has_pieces() const;

  // What a branch point (min, max, abs; numbered as in FieldPiece::branch) makes where it
  // switches. Smooth: its two branches meet with equal value and gradient (C1: a rounded box's
  // max(|x| - a, 0)^2, a smooth union's clamp), so no crease anywhere. Creased: their normals
  // differ somewhere (a sharp union, intersection or difference). Hidden: wherever it was seen
  // switching, flipping it changed nothing, to the last bit (a later min or max took the other
  // argument: the abs in a rounded box's max(|x| - a, 0)). Unknown: never seen switching on the
  // surface (an onion's abs(d) - t switches at d = 0, between its two shells). Pieces never
  // split a Smooth branch point, nor a Hidden one in a field with Smooth ones: those are
  // kFreeBranch in every piece; the others are split where their switch is near.
  enum class BranchKind : std::uint8_t { Unknown, Hidden, Smooth, Creased };
  // Every branch point's kind, found once (the first call; thread-safe, and the same whatever
  // the thread or order of the calls) from a grid of kBranchSamples^3 cell centres over
  // bounds(): where a branch point's switch lies within half a cell's diagonal of a sample, the
  // point where the switch meets the surface is sought from there (minimum-norm Newton steps on
  // the switch and on F, at most kBranchSurfaceSteps, the other branch points as taken at the
  // sample), and the field's normals with either branch compared there. Smooth only when every
  // such test (at most kBranchTests a branch point) found the same normal to kSamePieceCosine;
  // one difference makes it Creased. Counted as value_gradient evaluations. Empty for a model
  // without branch points.
  // \return the kinds, numbered as in FieldPiece::branch; the reference lives as long as the field.
  // \throw as value() (on the first call, which evaluates the field).
  const std::vector<BranchKind>& branch_kinds() const;
  static constexpr int kBranchSamples = 16;
  static constexpr int kBranchTests = 8;
  // On the surface and the switch: |F| / |grad F| and the distance to the switch below this
  // share of a cell, where the steps end (a rounded box's max(|z| - c, 0) switches its radius
  // inside its flat faces too, and an onion's abs(d) - t midway between its shells: kinks of the
  // field the surface never meets).
  static constexpr double kBranchOnSurface = 1e-3;
  // Where the two sides' normals agree on the surface, the branches are compared this share of a
  // cell off the switch too: a choice a smooth boolean's saturated clamp multiplies by 0 (a box's
  // switch where the other box's face is the surface) gives the same value there as well, and
  // tells nothing; a C1 switch (max(x, 0)^2, the clamp itself) does not. Taken for Smooth, a
  // box's switch between its top and its sides, met only behind the other box's face, was never
  // split, and the walks along its vertical edges stopped a step short of its corners.
  static constexpr double kBranchHiddenProbe = 0.1;
  // At most this many steps from a sample onto the surface along a switch.
  static constexpr int kBranchSurfaceSteps = 8;
  // A switch whose normal and the surface's are this sine apart at the least (about 3 degrees)
  // crosses the surface; a (nearly) parallel one is not followed.
  static constexpr double kBranchSwitchAcross = 0.05;
  // Whether the model promises a regular zero set: its gradient continuous and nonzero wherever
  // the surface passes, so no crease, cusp or singular point (the VIS, MPU, blob and analytic
  // models, whose fits and kernels are C1 and whose special points, a sphere's centre or a
  // torus's core circle, lie off the surface; compiled models whose authors say so). The
  // adaptive method's repair then asks no numeric crease probes (three evaluations per vertex
  // it touches). False by default: a callable field may hide a crease (an if on the
  // coordinates), and an expression too (sqrt(x^2) is |x|; a polynomial may have a node on its
  // zero set, x^2 + y^2 - z^2), which only the probes find.
  virtual bool smooth() const { return false; }
  // The step of the central differences this model's derivatives come from (a black box, such
  // as a Python function given without its derivatives: its curvature comes from differences
  // of values this far apart), or none where they are exact. A bend tighter than that step is
  // beyond what those derivatives resolve: where a run fails on one, the adaptive polygonizer
  // reports a crease the field does not describe instead of meshing again (adaptive_polygonizer.cpp).
  virtual std::optional<double> derivative_step() const { return std::nullopt; }
  // The spacing of the samples the model interpolates (a sampled volume's smallest), or none for
  // a model that is not sampled. Its interpolant has no detail of its own far below that
  // spacing: a bend much tighter is where the level passes near a saddle of it, which a scan's
  // noise puts everywhere; the adaptive polygonizer does not mesh such a run again
  // (failure_message.h).
  virtual std::optional<double> sample_spacing() const { return std::nullopt; }
  // Where branch point k (numbered as in FieldPiece::branch) switches near p, to first order:
  // the signed distance to the surface where its two arguments are equal ((a - b) / |grad (a - b)|,
  // u / |grad u| for abs) and that surface's unit normal, from one evaluation with the branches
  // as taken at p. Nothing for a model without such a branch point or where the difference has no
  // gradient. Crease tracing follows a switch past where the two pieces it separates become one
  // (trace_creases). Counted as one value_gradient.
  // \throw as value().
  struct BranchSwitch {
    double distance = 0;
    Vec3 normal = Vec3::Zero();
  };
  std::optional<BranchSwitch> branch_switch(const Vec3& p, std::size_t k) const;
  // Which branch points the value of the piece with `branch` depends on at p: bit k for branch
  // point k < 64 whose chosen argument reaches the value, not discarded by a later min or max
  // (a blend's clamp that multiplies it by 0 does not discard it). Crease tracing tells so where
  // a seam crosses a switch that shapes the pieces beside it (trace_creases). Nothing for a
  // model that cannot tell. Counted as one value_gradient.
  // \pre no kFreeBranch in `branch`.
  // \throw as value().
  std::optional<std::uint64_t> live_branches(const Vec3& p, const std::vector<std::uint8_t>& branch) const;
  // The far side of each C1 seam near p: for every Smooth branch point (branch_kinds) whose
  // switch lies within `radius` of p (to first order), that distance and the piece with its
  // branch flipped (the others as taken at p), evaluated at p: the surface beyond the seam,
  // continued to p. Where the curvature jumps across a seam (a rounded box's flat face meeting
  // its rounded edge, a smooth union's blend meeting the shapes it joins), the adaptive
  // polygonizer's sizing sees the curved side before its fronts reach it. Empty for a model
  // without Smooth branch points. Counted as one value_gradient and a gradient_hessian per side.
  // \throw as value() (a first call also classifies the branch points: branch_kinds).
  struct SmoothSide {
    double distance = 0;
    FieldPiece piece;
  };
  std::vector<SmoothSide> smooth_sides(const Vec3& p, double radius) const {
    return eval_smooth_sides(p, radius, {}, SeamSideAt::Point);
  }
  // Where smooth_sides evaluates the surface beyond a seam: continued to p (Point), or at the
  // switch's point nearest p, to first order (Seam), where that surface begins. They differ where
  // it bends unevenly: a smooth difference's fillet, a quadratic in its clamp's argument, has a
  // radius of 0.2 where it begins and of 1.4 continued 0.15 onto the face it joins.
  enum class SeamSideAt : std::uint8_t { Point, Seam };
  // The same on one piece (`branch` from pieces(): its branches fixed, the free ones as the values
  // choose): the seams of one face at a crease, where the field itself takes either face's branch
  // and sees only that face's seams. Evaluated where `at` says.
  // \throw InvalidInputError for a branch the model cannot have made (as piece()); else as value().
  std::vector<SmoothSide> smooth_sides(const Vec3& p, double radius, const std::vector<std::uint8_t>& branch,
                                       SeamSideAt at = SeamSideAt::Point) const {
    return eval_smooth_sides(p, radius, branch, at);
  }
  // The piece with `branch` (from pieces()) at another point: the same smooth function, its
  // branches fixed, wherever p is. Throws InvalidInputError for a branch the model cannot have
  // made. Counted as one gradient_hessian.
  // \throw InvalidInputError for a branch the model cannot have made: a non-empty one from a model
  //        without branch points, one of another length or with a choice above kFreeBranch from an
  //        expression, one whose length is not the number of calls of min, max and abs a
  //        compiled model (AutodiffField) makes at p. Otherwise as value().
  FieldPiece piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
    counter_.add_gradient_hessians(1);
    return eval_piece(p, branch);
  }
  // The value and gradient of piece(p, branch), the same numbers bit for bit, without its
  // Hessian (what crease tracing, the projections onto creases and the patch tests need).
  // Counted as one value_gradient.
  // \throw InvalidInputError as piece(), except from a compiled model (AutodiffField), which does not
  //        check the branch: choices past its calls are ignored, missing ones take the values' branch.
  //        Otherwise as value().
  std::pair<double, Vec3> piece_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
    counter_.add_value_gradients(1);
    return eval_first_order(p, branch);
  }

  // A box that contains the surface (the model's own, or the "bounds" given in its JSON).
  const Box& bounds() const { return bounds_; }
  // \pre no call of has_pieces, branch_kinds, pieces or smooth_sides came before: the branch kinds
  //      are found once, over the box of that first call.
  void set_bounds(const Box& b) { bounds_ = b; }

  // The model's type name as written in JSON ("sphere", "vis", ...).
  virtual std::string type_name() const = 0;

  // Whether evaluations (the const calls above) may run on several threads at once: true for a
  // model whose evaluation reads only its own immutable data. The core's data-parallel passes
  // (the seed grid) use threads only for such fields; results are the same either way. False by
  // default, so that a model with a cache, or one calling into an interpreter (a Python
  // function, which must hold its lock), is evaluated on the caller's thread only.
  virtual bool thread_safe() const { return false; }
  // Whether a call of the batched hooks costs far more than the arithmetic of its points: a
  // Python function, each call a trip into the interpreter. The adaptive polygonizer's blocks
  // then run in lockstep, the evaluations of many blocks gathered into one call
  // (polygonizer/src/adaptive/lockstep.h). False by default.
  // \pre true only for a model without branch points (a black box).
  virtual bool costly_calls() const { return false; }
  // Whether the adaptive method's repair should predict its tolerance estimates' edge midpoints
  // from the vertices' values, gradients and Hessians instead of evaluating the field there
  // (repair_context.h, kPredictShare): a model that is C2 or smoother, so that the predictions
  // hold between vertices, and whose points cost far more than the arithmetic around them (a
  // microsecond against a tenth of one: a VIS model of hundreds of centres). A Python function
  // given with its derivatives and called smooth is predicted too (its calls are costly). False by
  // default: on a cheap field the predictions cost more time than the evaluations they save (the
  // torus: 9 ns a value and gradient, 89 ns a Hessian), and an MPU model, costly too, is C1
  // wherever its kernels end (the predictions refused or their bounds raising the estimates: the
  // Igea MPU at 3e-4 came out with a 2-degree triangle).
  virtual bool predicts_from_hessians() const { return false; }

  // A bound L with |F(a) - F(b)| <= L |a - b| inside bounds(), when the model knows one.
  // Ray casting steps by |F| / L; models without a bound let the caller estimate one.
  virtual std::optional<double> lipschitz_bound() const { return std::nullopt; }
  // A bound that holds inside `region` (a box within bounds()); never larger than the global one.
  // Models whose steepness is local (blobs) override it, so that a search for small components
  // can prove most of the box empty (see the adaptive polygonizer's seeding).
  virtual std::optional<double> lipschitz_bound(const Box& region) const {
    (void)region;
    return lipschitz_bound();
  }

  // An interval [lo, hi] that contains F everywhere inside `region`, for models that can bound
  // their values (monotone kernels, interval arithmetic); nothing otherwise. Sharper than the
  // Lipschitz bound where a model knows more; the small-component search uses both.
  virtual std::optional<std::pair<double, double>> value_range(const Box& region) const {
    (void)region;
    return std::nullopt;
  }

  // Bounds (lo, hi) on each component of the gradient everywhere inside `region`, for models
  // that can bound them (a sampled volume, from its coefficients' differences); nothing
  // otherwise. Where some component's interval excludes zero the region holds no critical point
  // of F, so no small closed component of the surface lies around it: the seeding's band scan
  // skips such regions (seeding.cpp).
  virtual std::optional<std::pair<Vec3, Vec3>> gradient_range(const Box& region) const {
    (void)region;
    return std::nullopt;
  }

  // Bounds (lo, hi) on the derivative of F along the unit vector `direction` everywhere inside
  // `region`, for models that can bound it (an expression, by interval arithmetic; by default
  // from gradient_range); nothing otherwise. Where F is not differentiable (a crease of min or
  // max) the bounds hold every one-sided derivative, so bounds that exclude zero prove that the
  // region holds no critical point of F, smooth or not. Along a direction that crosses a crease,
  // such as the mean of the faces' normals across a box's edge, they can where no axis can.
  virtual std::optional<std::pair<double, double>> derivative_range(const Box& region, const Vec3& direction) const;
  // The bounds on the derivative along `direction` that bounds (lo, hi) on the gradient's
  // components give (derivative_range's default, for callers that have the gradient's at hand).
  static std::pair<double, double> derivative_range_of(const std::pair<Vec3, Vec3>& gradients, const Vec3& direction);

  // The minimum distance between two constraint points of a data-driven model; the paper's
  // Marching Tetrahedra "precision" convention scales this. Empty for models without points.
  virtual std::optional<double> constraint_spacing() const { return std::nullopt; }

  // \return the evaluations counted by kind since construction or the last reset_counts().
  EvaluationCounts counts() const { return counter_.counts(); }
  void reset_counts() const { counter_.reset(); }

  // One evaluation's record of its branch points: `taken` the branch each took (0: first
  // argument of min and max, +u for abs; 1: second argument, -u), `distance` how far its switch
  // lies, to first order (|a - b| / |grad (a - b)|, |u| / |grad u| for abs), and `seam_step` the
  // Newton step from the point onto that switch (-(a - b) grad (a - b) / |grad (a - b)|^2);
  // `value` and `gradient` the field's there. (Public for the models' helpers in autodiff.h.)
  struct BranchRecord {
    std::vector<std::uint8_t> taken;
    std::vector<double> distance;
    std::vector<Vec3> seam_step;
    std::vector<Vec3> seam_normal;  // grad (a - b) / |grad (a - b)| (zero where it has none)
    double value = 0;
    Vec3 gradient = Vec3::Zero();
    void add(bool branch, double gap, const Vec3& slope);  // gap a - b, slope grad (a - b)
  };
  // The record of one evaluation at p, the branches as the values take them (the first step of
  // pieces(), without the pieces). Counted as one value_gradient.
  // \return false, the record left alone, for a model without branch points.
  // \throw as value().
  bool branch_record(const Vec3& p, BranchRecord& record) const {
    counter_.add_value_gradients(1);
    return has_branch_points() && eval_branch_record(p, {}, record);
  }
  // In a piece's branch (FieldPiece::branch, Field::piece), this choice at a branch point means
  // "the branch the values take": a switch with no crease (C1), which the piece follows.
  static constexpr std::uint8_t kFreeBranch = 2;

 protected:
  virtual double eval_value(const Vec3& p) const = 0;
  virtual double eval_value_gradient(const Vec3& p, Vec3& gradient) const = 0;
  virtual double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const = 0;
  // The batched hooks loop over the single-point ones by default, so a model that does not
  // override them gives the same numbers either way. Fields whose calls cost more than their
  // arithmetic (a Python function) override them to evaluate a batch in one call.
  virtual void eval_values(const Vec3* points, double* out, std::size_t n) const {
    for (std::size_t i = 0; i < n; ++i) out[i] = eval_value(points[i]);
  }
  virtual void eval_values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const {
    for (std::size_t i = 0; i < n; ++i) values[i] = eval_value_gradient(points[i], gradients[i]);
  }
  // The lattice's points, evaluated by eval_values.
  virtual void eval_values_on_lattice(const Vec3& origin, double step, int n, double* out) const {
    std::vector<Vec3> points(static_cast<std::size_t>(n) * n * n);
    for (int c = 0; c < n; ++c)
      for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a)
          points[(static_cast<std::size_t>(c) * n + b) * n + a] = origin + step * Vec3(a, b, c);
    eval_values(points.data(), out, points.size());
  }
  virtual void eval_gradients_hessians(const Vec3* points, double* values, Vec3* gradients, Mat3* hessians,
                                       std::size_t n) const {
    for (std::size_t i = 0; i < n; ++i) values[i] = eval_gradient_hessian(points[i], gradients[i], hessians[i]);
  }
  // By default the three batched hooks, each for a batch that is not empty.
  virtual void eval_together(const Batch& plain, const Batch& with_gradients, const Batch& with_hessians) const {
    if (plain.n > 0) eval_values(plain.points, plain.values, plain.n);
    if (with_gradients.n > 0)
      eval_values_gradients(with_gradients.points, with_gradients.values, with_gradients.gradients, with_gradients.n);
    if (with_hessians.n > 0)
      eval_gradients_hessians(with_hessians.points, with_hessians.values, with_hessians.gradients,
                              with_hessians.hessians, with_hessians.n);
  }

  // The pieces near p (Field::pieces; without Hessians, pieces_first_order, unless `hessians`):
  // from the model's record of its branch points at p and the kinds of its branch points. Models
  // with branch points override eval_branch_record, eval_first_order and eval_piece instead
  // (models/expression.h and models/autodiff_field.h).
  virtual std::vector<FieldPiece> eval_pieces(const Vec3& p, double radius, bool hessians) const;
  virtual FieldPiece eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const;
  // smooth_sides: from the record at p and the kinds (a field that stands for another, such as
  // one piece of it, passes the call on).
  virtual std::vector<SmoothSide> eval_smooth_sides(const Vec3& p, double radius, const std::vector<std::uint8_t>& branch,
                                                    SeamSideAt at) const;

  // Whether the model has branch points at all (cheap; the default: none).
  virtual bool has_branch_points() const { return false; }
  // One evaluation's record of the model's branch points at p (BranchRecord), taking `branch`
  // (as in FieldPiece::branch; kFreeBranch, or an empty `branch`: as the values choose); false
  // for a model without branch points.
  virtual bool eval_branch_record(const Vec3& p, const std::vector<std::uint8_t>& branch, BranchRecord& record) const {
    (void)p;
    (void)branch;
    (void)record;
    return false;
  }
  // The field's value and gradient with the given branches (kFreeBranch: as the values choose).
  virtual std::pair<double, Vec3> eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const;
  // One step of eval_first_order_flips: with `flip`, evaluate the branch with choice `choice`
  // flipped (0 <-> 1) and make the choice kFreeBranch if `hidden` says so; without, make it
  // kFreeBranch at once.
  struct ChoiceStep {
    int choice;
    bool flip;
  };
  // The steps in turn on `branch`, each flip's value and gradient, eval_first_order(p, branch
  // with the choice flipped) as the branch stands at its step, given to `hidden`. The same numbers,
  // bit for bit, as those calls one by one (the default); a model may get them more cheaply
  // (Expression: from one run, each flip recomputing only what its choice reaches).
  // \pre each flipped choice is 0 or 1.
  virtual void eval_first_order_flips(const Vec3& p, std::vector<std::uint8_t>& branch,
                                      std::span<const ChoiceStep> steps,
                                      const std::function<bool(double, const Vec3&)>& hidden) const;
  // In out[mask], for each mask < 2^split.size(), eval_first_order(p, base with choice split[j]
  // flipped for each bit j of mask): the same numbers, bit for bit, as those calls (the
  // default); Expression gets them from one run, in Gray code order, each a flip of the one
  // before. \pre each choice in `split` is 0 or 1 in `base`.
  virtual void eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base,
                                             std::span<const int> split,
                                             std::vector<std::pair<double, Vec3>>& out) const;
  // eval_piece (with `hessian`; else eval_first_order's numbers, the Hessian left alone) into
  // `piece`, and in `live` bit bits[k] for each branch point k with bits[k] >= 0 whose choice the
  // value depends on: its chosen argument reaches the value, not discarded by a later min or
  // max. \pre no kFreeBranch in `branch`. False (the default) where the model cannot tell;
  // pieces are then found by evaluating every combination.
  virtual bool eval_piece_live(const Vec3& p, const std::vector<std::uint8_t>& branch, const std::int8_t* bits,
                               bool hessian, FieldPiece& piece, std::uint64_t& live) const {
    (void)p, (void)branch, (void)bits, (void)hessian, (void)piece, (void)live;
    return false;
  }
  // In `reaches`, for each branch point, whether its choice can change the value with the other
  // choices as `branch` gives them: whether its result reaches the value without a later min or
  // max whose choice is given (not kFreeBranch) discarding it. Flipping a choice that does not
  // reach it gives the same numbers, bit for bit, at every point. False (the default) where the
  // model cannot tell.
  virtual bool choices_reaching(const std::vector<std::uint8_t>& branch, std::vector<std::uint8_t>& reaches) const {
    (void)branch, (void)reaches;
    return false;
  }

  // The pieces near p from the record there: every branch point whose switch lies within `radius`
  // and that is not Smooth is split into both branches (the nearest kMaxSplitBranchPoints),
  // each combination evaluated with eval_piece (eval_first_order without `hessians`); equal
  // pieces (the same numbers bit for bit) are kept once, the branches as taken first.
  std::vector<FieldPiece> pieces_near_branches(const Vec3& p, const BranchRecord& record, double radius,
                                               bool hessians) const;
  // pieces_near_branches' combinations where every choice is forced (no kFreeBranch in `base`):
  // a choice whose argument a later min or max discards changes nothing, whatever the others,
  // so a choice is tried both ways only where an evaluation depends on it (eval_piece_live),
  // depth first: one evaluation for each function the choices can make, not 2^n (a Menger
  // sponge at factor 3: 17,808 evaluations where every combination took 64,878). The same
  // pieces, in the same order, as evaluating all.
  // Nothing where the model does not report what its values depend on.
  std::optional<std::vector<FieldPiece>> pieces_of_live_choices(const Vec3& p, const std::vector<std::uint8_t>& base,
                                                                const std::vector<int>& split, bool hessians) const;
  // At most this many branch points are split into both branches at one point, the nearest
  // switches first: 2^6 = 64 pieces, more than any corner of a CSG shape has (a cube's has 3),
  // and a bound on the work for formulas with many nearly tied min and max.
  static constexpr int kMaxSplitBranchPoints = 6;
  Box bounds_;

 private:
  EvaluationCounter counter_;
  BranchKind switch_verdict(const Vec3& p, const BranchRecord& record, std::size_t b, double cell,
                            std::uint64_t& evaluations) const;
  mutable std::once_flag kinds_once_;
  mutable std::vector<BranchKind> kinds_;
  mutable std::vector<bool> free_;  // kFreeBranch in every piece (branch_kinds)
  mutable bool any_smooth_ = false;  // a Smooth branch point among them
};

}  // namespace cdp
