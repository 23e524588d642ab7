#include "lockstep.h"

#include <cdp/core/errors.h>

#include <algorithm>
#include <array>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
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

// The carriers' meeting point. The last of the live carriers to ask makes the batch of every
// carrier's request, holding the lock (the others all wait for it, so nothing is lost by that).
// Between their evaluations carriers compute on at most `cores` cores at once: a carrier holds a
// core from its start, or from its answer, until its next request or its end; answered carriers
// wait in line for a core (in the order of their batches; which runs first changes no number).
class Gather {
 public:
  Gather(const Field& field, std::size_t carriers, std::size_t cores)
      : field_(field), pending_(carriers, nullptr), has_core_(carriers, false), wake_(carriers),
        live_(carriers), free_cores_(std::max<std::size_t>(cores, 1)) {
    for (auto& rs : by_kind_) rs.reserve(carriers);
  }

  const Field& field() const { return field_; }
  std::uint64_t batches() const { return batches_; }

  // Carrier c starts: waits for a core.
  void enter(std::size_t c) {
    std::unique_lock lock(mutex_);
    line_.push_back(c);
    hand_out_cores();
    wake(lock);
    wake_[c].wait(lock, [&] { return has_core_[c]; });
  }

  void ask(std::size_t c, Request& r) {
    std::unique_lock lock(mutex_);
    pending_[c] = &r;
    ++waiting_;
    release_core(c);
    if (waiting_ == live_) execute();
    wake(lock);
    wake_[c].wait(lock, [&] { return has_core_[c]; });  // answered first: see execute()
    if (r.error) std::rethrow_exception(r.error);
  }

  // Carrier c has no task left (or never started: `computing` false): the batches go on without it.
  void leave(std::size_t c, bool computing = true) {
    std::unique_lock lock(mutex_);
    if (computing) release_core(c);
    --live_;
    if (live_ > 0 && waiting_ == live_) execute();
    wake(lock);
  }

 private:
  // The carriers given a core, woken with the lock let go (a carrier woken under it would wake
  // only to wait for it: two switches a turn instead of one); the lock is held again on return.
  void wake(std::unique_lock<std::mutex>& lock) {
    if (woken_.empty()) return;
    std::vector<std::size_t> waking;
    waking.swap(woken_);
    lock.unlock();
    for (const std::size_t c : waking) wake_[c].notify_one();
    lock.lock();
  }

  void release_core(std::size_t c) {
    has_core_[c] = false;
    ++free_cores_;
    hand_out_cores();
  }
  void hand_out_cores() {
    while (free_cores_ > 0 && !line_.empty()) {
      const std::size_t c = line_.front();
      line_.pop_front();
      --free_cores_;
      has_core_[c] = true;
      woken_.push_back(c);
    }
  }

  // Every pending request, by kind in carrier order: one call of the field per kind. Each request
  // gets its own call's outcome: the field's answer, or the error of the call that held its points
  // with those of the other tasks (which all meet it). Then the batch's carriers line up for cores.
  void execute() {
    for (auto& rs : by_kind_) rs.clear();
    for (Request* r : pending_)
      if (r) by_kind_[static_cast<std::size_t>(r->kind)].push_back(r);
    waiting_ = 0;
    for (std::size_t k = 0; k < kKinds; ++k) {
      const std::vector<Request*>& rs = by_kind_[k];
      if (rs.empty()) continue;
      std::exception_ptr error;
      try {
        std::size_t total = 0;
        for (const Request* r : rs) total += r->n;
        if (total > 0) {
          points_.clear();
          for (const Request* r : rs) points_.insert(points_.end(), r->points, r->points + r->n);
          values_.resize(total);
          ++batches_;
          switch (static_cast<Kind>(k)) {
            case Kind::Values:
              field_.values(points_.data(), values_.data(), total);
              break;
            case Kind::ValuesGradients:
              gradients_.resize(total);
              field_.values_gradients(points_.data(), values_.data(), gradients_.data(), total);
              break;
            case Kind::GradientsHessians:
              gradients_.resize(total);
              hessians_.resize(total);
              field_.gradients_hessians(points_.data(), values_.data(), gradients_.data(), hessians_.data(), total);
              break;
          }
          std::size_t at = 0;
          for (Request* r : rs) {
            const auto from = static_cast<std::ptrdiff_t>(at);
            std::copy_n(values_.begin() + from, r->n, r->values);
            if (r->gradients) std::copy_n(gradients_.begin() + from, r->n, r->gradients);
            if (r->hessians) std::copy_n(hessians_.begin() + from, r->n, r->hessians);
            at += r->n;
          }
        }
      } catch (...) {
        error = std::current_exception();
      }
      for (Request* r : rs) r->error = error;
    }
    for (std::size_t c = 0; c < pending_.size(); ++c)
      if (pending_[c]) pending_[c] = nullptr, line_.push_back(c);
    hand_out_cores();
  }

  const Field& field_;
  std::mutex mutex_;
  std::vector<Request*> pending_;  // per carrier
  std::vector<bool> has_core_;     // per carrier
  std::vector<std::condition_variable> wake_;  // per carrier
  std::deque<std::size_t> line_;   // carriers ready to compute, waiting for a core
  std::vector<std::size_t> woken_;  // given a core, to be notified (wake())
  std::size_t live_, waiting_ = 0, free_cores_;
  std::uint64_t batches_ = 0;
  std::array<std::vector<Request*>, kKinds> by_kind_;
  std::vector<Vec3> points_;  // the batch's, reused
  std::vector<double> values_;
  std::vector<Vec3> gradients_;
  std::vector<Mat3> hessians_;
};

// The field as one carrier evaluates it.
class LockstepView final : public Field {
 public:
  LockstepView(Gather& gather, std::size_t carrier) : gather_(gather), field_(gather.field()), carrier_(carrier) {
    set_bounds(field_.bounds());
  }

  std::string type_name() const override { return field_.type_name(); }
  bool smooth() const override { return field_.smooth(); }
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

LockstepReport run_in_lockstep(const Field& field, std::size_t n, unsigned cores,
                               const std::function<void(const Field& view, std::size_t i)>& task) {
  LockstepReport report;
  if (n == 0) return report;
  const std::size_t carriers = std::min(n, kLockstepTasks);
  Gather gather(field, carriers, cores);
  std::vector<std::exception_ptr> errors(n);
  const auto carry = [&](std::size_t c) {
    gather.enter(c);
    {
      LockstepView view(gather, c);
      for (std::size_t i = c; i < n; i += carriers) try {
          task(view, i);
        } catch (...) {
          errors[i] = std::current_exception();
        }
    }
    gather.leave(c);
  };
  std::vector<std::thread> threads;
  threads.reserve(carriers);
  std::exception_ptr start_error;
  std::size_t started = 0;
  try {
    for (; started < carriers; ++started) threads.emplace_back(carry, started);
  } catch (...) {
    // The carriers that did start finish their tasks; those that did not leave the batches.
    start_error = std::current_exception();
    for (std::size_t c = started; c < carriers; ++c) gather.leave(c, false);
  }
  for (std::thread& t : threads) t.join();
  if (start_error) try {
      std::rethrow_exception(start_error);
    } catch (const std::system_error& e) {
      throw LimitExceededError(std::string("adaptive: the threads of tasks in lockstep could not start: ") + e.what());
    }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  report.carriers = carriers;
  report.batches = gather.batches();
  return report;
}

}  // namespace cdp::adaptive
