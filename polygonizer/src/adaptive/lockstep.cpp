#include "lockstep.h"

#include <cdp/core/errors.h>

#include "../fiber.h"
#include "../helper_thread.h"
#include "../parallel.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace cdp::adaptive {
namespace {

// How long a worker waiting for a round spins before it sleeps (see Gather::spin_until_round_after),
// reading the clock every kSpinsPerClockRead pauses.
constexpr std::chrono::microseconds kRoundSpin{200};
constexpr int kSpinsPerClockRead = 64;

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

// The carriers' meeting point. Each carrier is a fiber (fiber.h), and `workers` threads run them,
// carrier c on worker c % workers: a worker resumes each of its carriers in turn until it asks
// for an evaluation or ends, then waits for the round, the others' carriers asking too; the last
// worker to arrive makes the batch of every carrier's request and starts the next round. Between
// their evaluations carriers compute on at most `workers` cores at once, and a round costs a
// worker two fiber switches a carrier and one wait, where a thread a carrier cost every carrier
// two thread switches (the torus of python/README.md at factor 8, 64 carriers: 90,000 context
// switches and 0.8 s of system time in a 1.4 s run). Which worker runs a carrier changes no number.
class Gather {
 public:
  Gather(const Field& field, std::size_t carriers)
      : field_(field), pending_(carriers, nullptr), fibers_(carriers) {
    for (auto& rs : by_kind_) rs.reserve(carriers);
  }

  const Field& field() const { return field_; }
  std::uint64_t batches() const { return batches_; }
  std::vector<std::unique_ptr<detail::Fiber>>& fibers() { return fibers_; }

  // The workers' count, once their threads are known to run: workers wait for it.
  void open(std::size_t workers) {
    std::lock_guard lock(mutex_);
    workers_ = live_workers_ = workers;
    round_changed_.notify_all();
  }

  // Called by carrier c, inside its fiber: the request waits for its round's batch.
  void ask(std::size_t c, Request& r) {
    pending_[c] = &r;
    fibers_[c]->suspend();
    if (r.error) std::rethrow_exception(r.error);
  }

  // Worker w's loop, to the end of its carriers.
  void work(std::size_t w) {
    {
      std::unique_lock lock(mutex_);
      round_changed_.wait(lock, [&] { return workers_ > 0; });
      if (w >= workers_) return;  // its thread started, a later one did not: not a worker
    }
    for (;;) {
      bool done = true;
      for (std::size_t c = w; c < fibers_.size(); c += workers_) {
        detail::Fiber& f = *fibers_[c];
        if (!f.finished()) f.resume();
        done = done && f.finished();
      }
      std::unique_lock lock(mutex_);
      if (done) {
        --live_workers_;
        if (live_workers_ > 0 && arrived_ == live_workers_) next_round();
        return;
      }
      if (++arrived_ == live_workers_) {
        next_round();
      } else {
        const std::uint64_t round = round_.load(std::memory_order_relaxed);
        lock.unlock();
        if (spin_until_round_after(round)) continue;
        lock.lock();
        round_changed_.wait(lock, [&] { return round_.load(std::memory_order_relaxed) != round; });
      }
    }
  }

 private:
  // Holding the lock, every other live worker waiting.
  void next_round() {
    execute();
    arrived_ = 0;
    round_.fetch_add(1, std::memory_order_release);  // the answers before it (see spin_until_round_after)
    round_changed_.notify_all();
  }

  // Whether the round after `round` began within kRoundSpin. A round is a batch's call and the
  // carriers' steps between two evaluations, about a tenth of a millisecond; a worker put to sleep
  // takes tens of microseconds to wake (on two workers, sleeping at once made the torus of
  // python/README.md at factor 8 a third slower than one worker).
  bool spin_until_round_after(std::uint64_t round) const {
    const auto until = std::chrono::steady_clock::now() + kRoundSpin;
    for (int spins = 1;; ++spins) {
      if (round_.load(std::memory_order_acquire) != round) return true;
      if (spins % kSpinsPerClockRead == 0 && std::chrono::steady_clock::now() > until) return false;
      detail::spin_pause();
    }
  }

  // Every pending request, by kind in carrier order: one call of the field per kind. Each request
  // gets its own call's outcome: the field's answer, or the error of the call that held its points
  // with those of the other tasks (which all meet it).
  void execute() {
    for (auto& rs : by_kind_) rs.clear();
    for (Request*& r : pending_)
      if (r) by_kind_[static_cast<std::size_t>(r->kind)].push_back(std::exchange(r, nullptr));
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
  }

  const Field& field_;
  std::mutex mutex_;
  std::condition_variable round_changed_;
  std::vector<Request*> pending_;  // per carrier, written by its fiber, read by the round's last worker
  std::vector<std::unique_ptr<detail::Fiber>> fibers_;  // per carrier
  std::size_t workers_ = 0, live_workers_ = 0, arrived_ = 0;
  std::atomic<std::uint64_t> round_{0};  // written holding mutex_, read by spinning workers without it
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
  // This thread is the first worker, with the thread-local state a fresh thread has (the run's
  // pass clock and lent helper are not the tasks'); the others are threads of their own, as many
  // as start (fewer workers change no number).
  const std::size_t wanted = std::clamp<std::size_t>(cores, 1, carriers);
  std::vector<std::thread> helpers;
  helpers.reserve(wanted - 1);
  for (std::size_t w = 1; w < wanted; ++w) try {
      helpers.emplace_back([&gather, w] { gather.work(w); });
    } catch (const std::system_error&) {
      break;
    }
  gather.open(helpers.size() + 1);
  {
    const detail::ScopedPassClock no_clock;
    const detail::NoHelperHere no_helper;
    gather.work(0);
  }
  for (std::thread& t : helpers) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  report.carriers = carriers;
  report.batches = gather.batches();
  return report;
}

}  // namespace cdp::adaptive
