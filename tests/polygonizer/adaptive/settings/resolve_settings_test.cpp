// The settings stage (polygonizer/src/adaptive/resolve_settings.h): the options with every default
// resolved, and bad options refused before anything is evaluated.
#include <gtest/gtest.h>

#include "src/adaptive/resolve_settings.h"

#include <cdp/core/errors.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "polygonizer/adaptive/stage_fixtures.h"

namespace cdp::adaptive {
namespace {

using namespace test_stages;

TEST(AdaptiveStages, SettingsResolveTheDefaultsFromTheBoxAndRefuseBadOptions) {
  const auto field = test::field_from_json(kSphere);
  const double diagonal = field->bounds().diagonal();
  const Settings s = resolve_settings(*field, AdaptiveOptions{});
  EXPECT_DOUBLE_EQ(s.diagonal, diagonal);
  EXPECT_DOUBLE_EQ(s.sizing.min_edge, 2e-3 * diagonal);
  EXPECT_DOUBLE_EQ(s.sizing.max_edge, 0.1 * diagonal);
  EXPECT_EQ(s.sizing.factor, 2);
  AdaptiveOptions tol;
  tol.sizing = SizingMode::Tolerance;
  tol.tolerance = 1e-3;
  EXPECT_LT(resolve_settings(*field, tol).sizing.tolerance, 1e-3);  // the sizing keeps a share for the refinement
  EXPECT_DOUBLE_EQ(requested_tolerance(tol, s), 1e-3);
  for (const auto& [what, set] : std::vector<std::pair<std::string, std::function<void(AdaptiveOptions&)>>>{
           {"nan tolerance", [](AdaptiveOptions& o) { o.tolerance = std::nan(""); }},
           {"min_edge above max_edge", [](AdaptiveOptions& o) { o.min_edge = 1, o.max_edge = 0.5; }},
           {"factor 0", [](AdaptiveOptions& o) { o.factor = 0; }},
           {"seed_resolution 1", [](AdaptiveOptions& o) { o.seed_resolution = 1; }}}) {
    AdaptiveOptions o;
    set(o);
    EXPECT_THROW(resolve_settings(*field, o), InvalidInputError) << what;
  }
  EXPECT_TRUE(remeshing_allowed(AdaptiveOptions{}));
  AdaptiveOptions bounded;
  bounded.max_triangles = 100;
  EXPECT_FALSE(remeshing_allowed(bounded));
}

}  // namespace
}  // namespace cdp::adaptive
