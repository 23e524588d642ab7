#include "lockstep.h"

#include <cdp/core/errors.h>

#include "../fiber.h"
#include "../helper_thread.h"
#include "../parallel.h"

#include <algorithm>
#include <array>
#include <exception>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace cdp::adaptive {
namespace {

enum class Kind : std::uint8_t { Values, ValuesGradients, GradientsHessians };
constexpr std::size_t kKinds = 3;

// One carrier's evaluation, waiting for its batch.
struct Request {
  Kind kind;
  const Vec3* points;
  double* values;
  Vec3* gradients;  // null for Values
  Mat3* hessians;   // null but for GradientsHessians
  std::size_t n;
  std::exception_ptr error;
};

// The carriers' meeting point. Each carrier is a fiber (fiber.h), all of them on the calling
// thread: a round resumes each carrier in turn until it asks for an evaluation or ends, then makes
// the batch of every carrier's request. A round costs two fiber switches a carrier, where a thread
// a carrier cost every carrier two thread switches (the torus of python/README.md at factor 8, 64
// carriers: 90,000 context switches and 0.8 s of system time in a 1.4 s run; 0.25 s now). One
// thread, not one per core: with the carriers shared by two threads meeting once a round, the
// same runs took 1.1-1.7 times as long on this 2-core machine (a Python function's calls then
// come from two threads, and each round waits for the slower one).
class Gather {
 public:
  Gather(const Field& field, std::size_t carriers) : field_(field), pending_(carriers, nullptr), fibers_(carriers) {
    for (auto& rs : by_kind_) rs.reserve(carriers);
  }

  const Field& field() const { return field_; }
  std::uint64_t batches() const { return batches_; }
  std::vector<std::unique_ptr<detail::Fiber>>& fibers() { return fibers_; }

  // Called by carrier c, inside its fiber: the request waits for its round's batch.
  void ask(std::size_t c, Request& r) {
    pending_[c] = &r;
    fibers_[c]->suspend();
    if (r.error) std::rethrow_exception(r.error);
  }

  // The rounds, to the end of every carrier: each round advances every carrier left by one
  // evaluation (a carrier suspends only to ask), so the rounds are as many as the most
  // evaluations one carrier's tasks make.
  void run() {
    for (;;) {
      bool any = false;
      for (const auto& f : fibers_)
        if (!f->finished()) {
          f->resume();
          any = any || !f->finished();
        }
      if (!any) return;
      execute();
    }
  }

 private:
  // Every pending request, by kind in carrier order, the three kinds in one evaluation of the field
  // (Field::evaluate_together: one call of a Python function where three would cost three trips
  // into the interpreter; the torus of python/README.md at factor 8: 3,441 calls in 1,912 rounds).
  // Each request gets the round's outcome: the field's answer, or the error of the call that held
  // its points with those of the other tasks (which all meet it).
  void execute() {
    for (auto& rs : by_kind_) rs.clear();
    for (Request*& r : pending_)
      if (r) by_kind_[static_cast<std::size_t>(r->kind)].push_back(std::exchange(r, nullptr));
    std::exception_ptr error;
    try {
      std::array<Field::Batch, kKinds> batches;
      std::size_t total = 0;
      for (std::size_t k = 0; k < kKinds; ++k) {
        KindBuffers& b = buffers_[k];
        b.points.clear();
        for (const Request* r : by_kind_[k]) b.points.insert(b.points.end(), r->points, r->points + r->n);
        const std::size_t n = b.points.size();
        b.values.resize(n);
        if (k != static_cast<std::size_t>(Kind::Values)) b.gradients.resize(n);
        if (k == static_cast<std::size_t>(Kind::GradientsHessians)) b.hessians.resize(n);
        batches[k] = {b.points.data(), b.values.data(), b.gradients.data(), b.hessians.data(), n};
        total += n;
      }
      if (total > 0) {
        ++batches_;
        field_.evaluate_together(batches[0], batches[1], batches[2]);
      }
      for (std::size_t k = 0; k < kKinds; ++k) {
        const KindBuffers& b = buffers_[k];
        std::size_t at = 0;
        for (Request* r : by_kind_[k]) {
          const auto from = static_cast<std::ptrdiff_t>(at);
          std::copy_n(b.values.begin() + from, r->n, r->values);
          if (r->gradients) std::copy_n(b.gradients.begin() + from, r->n, r->gradients);
          if (r->hessians) std::copy_n(b.hessians.begin() + from, r->n, r->hessians);
          at += r->n;
        }
      }
    } catch (...) {
      error = std::current_exception();
    }
    for (const auto& rs : by_kind_)
      for (Request* r : rs) r->error = error;
  }

  // A kind's points and results in a round, reused.
  struct KindBuffers {
    std::vector<Vec3> points;
    std::vector<double> values;
    std::vector<Vec3> gradients;
    std::vector<Mat3> hessians;
  };

  const Field& field_;
  std::vector<Request*> pending_;  // per carrier
  std::vector<std::unique_ptr<detail::Fiber>> fibers_;  // per carrier
  std::uint64_t batches_ = 0;
  std::array<std::vector<Request*>, kKinds> by_kind_;
  std::array<KindBuffers, kKinds> buffers_;
};

// The field as one carrier evaluates it.
class LockstepView final : public Field {
 public:
  LockstepView(Gather& gather, std::size_t carrier) : gather_(gather), field_(gather.field()), carrier_(carrier) {
    set_bounds(field_.bounds());
  }

  std::string type_name() const override { return field_.type_name(); }
  bool smooth() const override { return field_.smooth(); }
  bool predicts_from_hessians() const override { return field_.predicts_from_hessians(); }
  std::optional<double> derivative_step() const override { return field_.derivative_step(); }
  std::optional<double> sample_spacing() const override { return field_.sample_spacing(); }
  std::optional<double> lipschitz_bound() const override { return field_.lipschitz_bound(); }
  std::optional<double> lipschitz_bound(const Box& region) const override { return field_.lipschitz_bound(region); }
  std::optional<std::pair<double, double>> value_range(const Box& region) const override {
    return field_.value_range(region);
  }
  std::optional<std::pair<Vec3, Vec3>> gradient_range(const Box& region) const override {
    return field_.gradient_range(region);
  }
  std::optional<std::pair<double, double>> derivative_range(const Box& region, const Vec3& direction) const override {
    return field_.derivative_range(region, direction);
  }
  std::optional<double> constraint_spacing() const override { return field_.constraint_spacing(); }

 protected:
  double eval_value(const Vec3& p) const override {
    double v;
    eval_values(&p, &v, 1);
    return v;
  }
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override {
    double v;
    eval_values_gradients(&p, &v, &gradient, 1);
    return v;
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override {
    double v;
    eval_gradients_hessians(&p, &v, &gradient, &hessian, 1);
    return v;
  }
  void eval_values(const Vec3* points, double* out, std::size_t n) const override {
    Request r{Kind::Values, points, out, nullptr, nullptr, n, {}};
    gather_.ask(carrier_, r);
  }
  void eval_values_gradients(const Vec3* points, double* values, Vec3* gradients, std::size_t n) const override {
    Request r{Kind::ValuesGradients, points, values, gradients, nullptr, n, {}};
    gather_.ask(carrier_, r);
  }
  void eval_gradients_hessians(const Vec3* points, double* values, Vec3* gradients, Mat3* hessians,
                               std::size_t n) const override {
    Request r{Kind::GradientsHessians, points, values, gradients, hessians, n, {}};
    gather_.ask(carrier_, r);
  }

 private:
  Gather& gather_;
  const Field& field_;
  std::size_t carrier_;
};

}  // namespace

LockstepReport run_in_lockstep(const Field& field, std::size_t n,
                               const std::function<void(const Field& view, std::size_t i)>& task) {
  LockstepReport report;
  if (n == 0) return report;
  const std::size_t carriers = std::min(n, kLockstepTasks);
  Gather gather(field, carriers);
  std::vector<std::exception_ptr> errors(n);
  try {
    for (std::size_t c = 0; c < carriers; ++c)
      gather.fibers()[c] = std::make_unique<detail::Fiber>([&, c] {
        LockstepView view(gather, c);
        for (std::size_t i = c; i < n; i += carriers) try {
            task(view, i);
          } catch (...) {
            errors[i] = std::current_exception();
          }
      });
  } catch (const std::bad_alloc&) {
    throw LimitExceededError("adaptive: the stacks of " + std::to_string(carriers) +
                             " tasks in lockstep could not be mapped");
  }
  {
    // The tasks have none of this thread's thread-local state (the run's pass clock, a lent
    // helper), as on threads of their own.
    const detail::ScopedPassClock no_clock;
    const detail::NoHelperHere no_helper;
    gather.run();
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  report.carriers = carriers;
  report.batches = gather.batches();
  return report;
}

}  // namespace cdp::adaptive
