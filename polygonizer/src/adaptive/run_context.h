// What the stages of one run share: the field, the caller's options and the phase ledger.
#pragma once

#include "phase_ledger.h"

#include <cdp/core/adaptive_polygonizer.h>

#include <string_view>

namespace cdp::adaptive {

struct RunContext {
  const Field& field;
  const AdaptiveOptions& options;
  PhaseLedger& phases;

  // Enters a phase of kAdaptivePhases: the caller's cancel token is polled first (a cancelled
  // run stops between phases too), and AdaptiveOptions::phase is told `text` where one is given.
  // \throw CancelledError
  void enter(std::string_view phase, const char* text = nullptr) const {
    options.cancel.check("adaptive");
    phases.enter(phase);
    if (text && options.phase) options.phase(text);
  }
};

}  // namespace cdp::adaptive
