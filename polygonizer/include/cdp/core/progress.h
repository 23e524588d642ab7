// How long computations report progress: algorithms take a ProgressCallback (and a
// PhaseCallback) in their options and call them; what is shown, and where, is the caller's
// business (the programs draw a bar on a terminal or print lines with --progress).
#pragma once

#include <functional>
#include <string>

namespace cdp {

// A fraction in [0, 1] of the current phase, non-decreasing within it.
using ProgressCallback = std::function<void(double fraction)>;
// The name of the phase a computation enters ("sampling the seed grid", "meshing", "checking
// the mesh"); fractions restart at 0 in each phase.
using PhaseCallback = std::function<void(const std::string& phase)>;

}  // namespace cdp
