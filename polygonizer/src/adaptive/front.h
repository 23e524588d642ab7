// Fronts: closed polygons of mesh vertices bounding the part of the surface not meshed yet.
//
// A front is a doubly linked list of nodes. A node is one occurrence of a mesh vertex on a
// front: after a split or a merge the two end points of the new bridge edge occur twice, so
// nodes and vertices are distinct. Orientation: the unmeshed region lies to the left of every
// front edge node -> next seen from outside, so a triangle built on front edge (u, next(u))
// with a new apex x is (u, next(u), x), counter-clockwise seen from outside.
//
// Each front keeps a min-heap of (front angle, node) with lazy deletion: a node's version is
// bumped whenever its angle or its front changes, and heap entries with an old version or a
// foreign front are dropped when they surface.
//
// The nodes and the heaps grow with a cancel poll between blocks (polled_growth.h): they hold
// millions of entries at 2*10^6 triangles, and one doubling of them was a tenth of a second.
#pragma once

#include "../polled_growth.h"

#include <cdp/core/cancel.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace cdp::adaptive {

struct FrontNode {
  int vertex = -1;
  int prev = -1, next = -1;
  int front = -1;  // -1 once the node has left every front
  std::uint32_t version = 0;
  double angle = 0;
};

struct HeapEntry {
  double angle;
  int node;
  std::uint32_t version;
  // The heap (std::push_heap) is a max-heap; "less" here means "expanded later". Ties go to
  // the lower node id so the order never depends on heap internals.
  bool operator<(const HeapEntry& o) const { return angle != o.angle ? angle > o.angle : node > o.node; }
};

struct Front {
  int size = 0;
  bool alive = false;
  int stall = 0;  // deferrals since the front last advanced
  std::vector<HeapEntry> heap;  // std::push_heap's order
  // Frees the heap of a front that is done (`heap = {}` would keep its capacity).
  void release_heap() { std::vector<HeapEntry>().swap(heap); }
};

struct FrontSet {
  std::vector<FrontNode> nodes;
  std::vector<Front> fronts;
  CancelToken cancel;  // the run's, polled while nodes and heaps grow

  int new_front() {
    fronts.emplace_back();
    fronts.back().alive = true;
    return static_cast<int>(fronts.size()) - 1;
  }
  int new_node(int vertex, int front) {
    FrontNode n;
    n.vertex = vertex;
    n.front = front;
    detail::grow_apart(cancel, "adaptive", 1, nodes);
    nodes.push_back(n);
    ++fronts[front].size;
    return static_cast<int>(nodes.size()) - 1;
  }
  void link(int a, int b) {
    nodes[a].next = b;
    nodes[b].prev = a;
  }
  // Smallest-angle node of the front with a current heap entry, or -1 when none is left.
  int pop_min(int front) {
    auto& heap = fronts[front].heap;
    while (!heap.empty()) {
      std::pop_heap(heap.begin(), heap.end());
      const HeapEntry e = heap.back();
      heap.pop_back();
      const FrontNode& n = nodes[e.node];
      if (n.front == front && n.version == e.version) return e.node;
    }
    return -1;
  }
  void push(int node) { push_with_key(node, nodes[node].angle); }
  // Queues the node under another key than its angle (to postpone it).
  void push_with_key(int node, double key) {
    FrontNode& n = nodes[node];
    ++n.version;
    std::vector<HeapEntry>& heap = fronts[n.front].heap;
    detail::grow_apart(cancel, "adaptive", 1, heap);
    heap.push_back({key, node, n.version});
    std::push_heap(heap.begin(), heap.end());
  }
};

}  // namespace cdp::adaptive
