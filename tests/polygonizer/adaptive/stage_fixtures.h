// What the stage tests share (tests/polygonizer/adaptive/*/stage_*_test.cpp): a few fields and
// the context of one run, so that each stage runs alone on its typed input
// (polygonizer/README.md, "How a run goes").
#pragma once

#include "src/adaptive/phase_ledger.h"
#include "src/adaptive/resolve_settings.h"
#include "src/adaptive/run_context.h"
#include "src/adaptive/stage_creases.h"
#include "src/adaptive/stage_seed_grid.h"
#include "src/adaptive/stage_tracking.h"

#include <memory>
#include <utility>

#include "common/test_fields.h"

namespace cdp::adaptive::test_stages {

inline const char* const kSphere = R"({"type": "sphere", "radius": 1})";
inline const char* const kTanglecube = R"({"type": "expression", "value": "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                                    "bounds": [[-3, -3, -3], [3, 3, 3]]})";
inline const char* const kCube = R"({"type": "expression", "value": "max(abs(x), max(abs(y), abs(z))) - 1",
                              "bounds": [[-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]]})";

// What the stages share in one run.
struct Stages {
  std::unique_ptr<Field> field;
  AdaptiveOptions options;
  PhaseLedger phases;
  RunContext run;
  Settings settings;
  explicit Stages(const char* json, AdaptiveOptions o = {})
      : field(test::field_from_json(json)), options(std::move(o)), phases(*field), run{*field, options, phases},
        settings(resolve_settings(*field, options)) {}
};

// The tracking stage on `seeds`, without crease patches, at the hash cell the seed grid measured.
inline void track(Stages& s, const SeedGridStage& seeds, Mesh& mesh, Tracking& tracking) {
  Settings settings = s.settings;
  settings.hash_cell = seeds.hash_cell;
  track_surface(s.run, seeds, nullptr, false, 0, settings, mesh, tracking);
}

}  // namespace cdp::adaptive::test_stages
