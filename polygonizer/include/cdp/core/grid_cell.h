// The cell of a point in a uniform grid of cubes of side h, and a hash of cells: the small
// hash grids of points and segments (crease tracing, crease distances) share them.
#pragma once

#include <cdp/core/field.h>

#include <array>
#include <cmath>
#include <cstdint>

namespace cdp {

using GridCell = std::array<std::int64_t, 3>;

inline GridCell grid_cell(const Vec3& p, double h) {
  return {static_cast<std::int64_t>(std::floor(p.x() / h)), static_cast<std::int64_t>(std::floor(p.y() / h)),
          static_cast<std::int64_t>(std::floor(p.z() / h))};
}

// Products with large odd constants, xored: distinct small cells rarely collide.
inline std::uint64_t grid_cell_key(const GridCell& c) {
  return static_cast<std::uint64_t>(c[0]) * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(c[1]) * 0xC2B2AE3D27D4EB4Full ^
         static_cast<std::uint64_t>(c[2]) * 0x165667B19E3779F9ull;
}

}  // namespace cdp
