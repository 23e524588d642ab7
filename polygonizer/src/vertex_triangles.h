// The triangles around each vertex, as one table (counting sort): vertex v's are
// incident[offsets[v]] .. incident[offsets[v + 1] - 1], in increasing order, a triangle with a
// repeated index once per occurrence, consecutively. Shared by the topology analysis and the
// self-intersection check's flat stars. Indices must be valid (callers check them first).
#pragma once

#include "polled_growth.h"

#include <cdp/core/cancel.h>
#include <cdp/core/mesh.h>

#include <cstddef>
#include <numeric>
#include <vector>

namespace cdp {

struct VertexTriangles {
  std::vector<int> offsets;  // num_vertices + 1
  std::vector<int> incident;

  // `cancel` (optional) is polled every kPollEvery triangles, with `what` in its error.
  static constexpr std::size_t kPollEvery = 4096;
  explicit VertexTriangles(const Mesh& mesh, const CancelToken* cancel = nullptr, const char* what = "")
      : offsets(mesh.positions.size() + 1, 0) {
    const auto poll = [&](std::size_t f) {
      if (cancel && f % kPollEvery == 0) cancel->check(what);
    };
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      poll(f);
      for (const int i : mesh.triangles[f]) ++offsets[static_cast<std::size_t>(i) + 1];
    }
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    // Zero-filled between polls: 24 MB of fresh pages at 2*10^6 triangles.
    incident = detail::polled_vector<int>(static_cast<std::size_t>(offsets.back()), [&] { poll(0); });
    std::vector<int> fill(offsets.begin(), offsets.end() - 1);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      poll(f);
      for (const int i : mesh.triangles[f]) incident[static_cast<std::size_t>(fill[static_cast<std::size_t>(i)]++)] = static_cast<int>(f);
    }
  }
};

}  // namespace cdp
