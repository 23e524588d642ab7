// STATS.json: PolygonizeStats as JSON. The common fields, then the method's report (the adaptive
// method's or the lattice methods'), then the mesh's angles, under the keys docs/stats.md lists.
#pragma once

#include <cdp/core/polygonize_stats.h>

#include <nlohmann/json.hpp>

namespace cdp {

// \return the STATS.json object of `stats` (keys sorted, as nlohmann::json keeps them).
nlohmann::json to_json(const PolygonizeStats& stats);

}  // namespace cdp
