// PhaseLedger: the time and field evaluations of each phase (kAdaptivePhases) of the runs
// polygonize_adaptive makes (AdaptiveReport::phases).
#pragma once

#include <cdp/core/adaptive_report.h>
#include <cdp/core/field.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace cdp::adaptive {

// Summed over every run polygonize_adaptive makes, failed and discarded ones included: the
// phases' evaluations add up to the run's field_evaluations exactly (nothing between runs
// evaluates), and their seconds to nearly all of its seconds (between runs: a discarded run's
// stats and destructors, the bounds a re-run is judged by, a fraction of a percent). A phase
// lasts from its entry to the next phase's or the run's end.
class PhaseLedger {
 public:
  explicit PhaseLedger(const Field& field) : field_(field) {}
  // \throw std::logic_error for a name not in kAdaptivePhases.
  void enter(std::string_view name) {
    close();
    const auto it = std::find(kAdaptivePhases.begin(), kAdaptivePhases.end(), name);
    if (it == kAdaptivePhases.end()) throw std::logic_error("PhaseLedger: no phase " + std::string(name));
    current_ = static_cast<int>(it - kAdaptivePhases.begin());
    start_ = std::chrono::steady_clock::now();
    counts_ = field_.counts();
  }
  // Ends the current phase (a run's end, or its error).
  void close() {
    if (current_ < 0) return;
    PhaseReport& e = entries_[current_];
    e.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    e.evaluations += field_.counts() - counts_;
    current_ = -1;
  }
  // Evaluations a run split with a helper thread (helper_thread.h).
  void add_split_evaluations(std::uint64_t n) { split_evaluations_ += n; }
  // Every phase, zero where no run entered it.
  void write(AdaptiveReport& report) const {
    report.split_evaluations = split_evaluations_;
    report.phases = entries_;
  }

 private:
  const Field& field_;
  std::array<PhaseReport, kAdaptivePhases.size()> entries_{};
  std::uint64_t split_evaluations_ = 0;
  int current_ = -1;
  std::chrono::steady_clock::time_point start_{};
  EvaluationCounts counts_;
};

// Closes the ledger's phase when a run ends, by its return or its error.
struct PhaseCloser {
  PhaseLedger& ledger;
  ~PhaseCloser() { ledger.close(); }
};

}  // namespace cdp::adaptive
