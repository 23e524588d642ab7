// The determinism tests' "the same mesh bit for bit": positions, triangles, normals and vertex
// scalars, each number compared by its bits (same_bits.h).
#pragma once

#include <gtest/gtest.h>

#include <cdp/core/mesh.h>

#include "common/same_bits.h"

#include <string>

namespace cdp::test {

inline void expect_same_mesh(const Mesh& a, const Mesh& b, const std::string& what = "") {
  SCOPED_TRACE(what);
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (std::size_t i = 0; i < a.positions.size(); ++i) ASSERT_TRUE(same_bits(a.positions[i], b.positions[i])) << "vertex " << i;
  for (std::size_t i = 0; i < a.triangles.size(); ++i) ASSERT_EQ(a.triangles[i], b.triangles[i]) << "triangle " << i;
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for (std::size_t i = 0; i < a.normals.size(); ++i) ASSERT_TRUE(same_bits(a.normals[i], b.normals[i])) << "normal " << i;
  ASSERT_EQ(a.vertex_scalars.size(), b.vertex_scalars.size());
  for (const auto& [name, values] : a.vertex_scalars) {
    ASSERT_TRUE(b.vertex_scalars.count(name)) << name;
    const std::vector<double>& other = b.vertex_scalars.at(name);
    ASSERT_EQ(values.size(), other.size()) << name;
    for (std::size_t i = 0; i < values.size(); ++i) ASSERT_TRUE(same_bits(values[i], other[i])) << name << " " << i;
  }
}

}  // namespace cdp::test
