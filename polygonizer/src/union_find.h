// Disjoint sets over 0..n-1 with path halving; a union keeps the smaller index as the root, so
// labels do not depend on the order of the unions. Shared by the seeding (crossed cells), the
// topology analysis (components, vertex fans) and the adaptive polygonizer's checks.
#pragma once

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace cdp {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) { reset(n); }
  // n singletons again, keeping the allocation.
  void reset(std::size_t n) {
    parent.resize(n);
    std::iota(parent.begin(), parent.end(), 0);
  }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace cdp
