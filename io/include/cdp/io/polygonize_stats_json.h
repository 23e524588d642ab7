// STATS.json: PolygonizeStats as JSON, the common fields first and then every method-specific
// figure (dotted names become nested objects).
#pragma once

#include <cdp/core/polygonize_stats.h>

#include <nlohmann/json.hpp>

namespace cdp {

nlohmann::json to_json(const PolygonizeStats& stats);

}  // namespace cdp
