// What every polygonization method returns: the mesh and the common statistics.
#pragma once

#include <polygonizer/mesh.h>
#include <polygonizer/polygonize_stats.h>

namespace cdp {

struct PolygonizeResult {
  Mesh mesh;
  PolygonizeStats stats;
};

}  // namespace cdp
