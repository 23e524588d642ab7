// Bitwise equality of doubles, vectors and matrices: the determinism tests' "the same bit for
// bit" (NaNs of the same payload compare equal, 0.0 and -0.0 do not).
#pragma once

#include <cdp/core/field.h>

#include <bit>
#include <cstdint>

namespace cdp::test {

inline bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

inline bool same_bits(const Vec3& a, const Vec3& b) {
  for (int k = 0; k < 3; ++k)
    if (!same_bits(a[k], b[k])) return false;
  return true;
}

inline bool same_bits(const Mat3& a, const Mat3& b) {
  for (int k = 0; k < 9; ++k)
    if (!same_bits(a.data()[k], b.data()[k])) return false;
  return true;
}

}  // namespace cdp::test
