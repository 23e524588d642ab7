// What every polygonization method returns: the mesh and the common statistics.
#pragma once

#include <cdp/core/mesh.h>
#include <cdp/core/polygonize_stats.h>

namespace cdp {

struct PolygonizeResult {
  Mesh mesh;
  PolygonizeStats stats;
};

}  // namespace cdp
