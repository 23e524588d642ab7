// unify-front (paper section 6, Figure 7): the candidate point p runs into a point q of another
// front. The bridge edge p-q joins both fronts into one; p and q then occur twice on it.
//
//   before:  a -> p -> b -> ... -> a        c -> q -> d -> ... -> c
//   after:   a -> p -> q -> d -> ... -> c -> q' -> p' -> b -> ... -> a
//
// Merging is how handles appear: on a torus the front that wrapped around meets itself from
// the other side after a split.
#include "tracker.h"

namespace cdp::adaptive {

int Tracker::merge_fronts(int p, int q) {
  ++merges_;
  const int f = fs_.nodes[p].front, g = fs_.nodes[q].front;
  // The smaller front's nodes are relabelled into the larger one.
  const bool keep_f = fs_.fronts[f].size >= fs_.fronts[g].size;
  const int keep = keep_f ? f : g, gone = keep_f ? g : f;
  const int b = fs_.nodes[p].next;
  const int c = fs_.nodes[q].prev;
  const int q2 = insert_node(fs_.nodes[q].vertex, keep);
  const int p2 = insert_node(fs_.nodes[p].vertex, keep);
  link(p, q);
  link(c, q2);
  link(q2, p2);
  link(p2, b);

  // Nodes of the absorbed front: q .. c when it was g, b .. a and p when it was f.
  const int first = keep_f ? q : b, last = keep_f ? c : p;
  for (int x = first;; x = fs_.nodes[x].next) {
    fs_.nodes[x].front = keep;
    fs_.push(x);
    if (x == last) break;
  }
  fs_.fronts[keep].size += fs_.fronts[gone].size;
  fs_.fronts[gone].size = 0;
  fs_.fronts[gone].alive = false;
  fs_.fronts[gone].release_heap();
  refresh(p);
  refresh(q);
  refresh(p2);
  refresh(q2);
  return keep;
}

}  // namespace cdp::adaptive
