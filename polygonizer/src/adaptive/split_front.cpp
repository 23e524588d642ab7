// split-front (paper section 6, Figure 8): the candidate point p runs into a point q of its own
// front. The bridge edge p-q cuts the unmeshed region in two; p and q then occur on both new
// fronts, as two nodes each.
//
//   before:  a -> p -> b -> ... -> c -> q -> d -> ... -> a
//   after:   p -> b -> ... -> c -> q -> p            (front 1, keeps p and q)
//            q' -> d -> ... -> a -> p' -> q'         (front 2, new nodes p' and q')
#include "tracker.h"

namespace cdp::adaptive {

void Tracker::split_front(int p, int q) {
  ++splits_;
  const int f = fs_.nodes[p].front;
  const int a = fs_.nodes[p].prev;
  const int d = fs_.nodes[q].next;
  const int p2 = insert_node(fs_.nodes[p].vertex, f);
  const int q2 = insert_node(fs_.nodes[q].vertex, f);
  link(q, p);
  link(a, p2);
  link(p2, q2);
  link(q2, d);

  // Walk both loops in step to find the shorter one; only that one moves to a new front, so
  // the relabelling costs the size of the smaller part.
  int x = p, y = q2, n1 = 0, n2 = 0;
  bool first_shorter = false;
  for (;;) {
    x = fs_.nodes[x].next, ++n1;
    if (x == p) {
      first_shorter = true;
      break;
    }
    y = fs_.nodes[y].next, ++n2;
    if (y == q2) break;
  }
  const int total = fs_.fronts[f].size;
  const int g = fs_.new_front();
  if (first_shorter) {
    relabel(p, g);
    fs_.fronts[g].size = n1;
    fs_.fronts[f].size = total - n1;
  } else {
    relabel(q2, g);
    fs_.fronts[g].size = n2;
    fs_.fronts[f].size = total - n2;
  }
  refresh(p);
  refresh(q);
  refresh(p2);
  refresh(q2);
  stack_.push_back(g);
}

}  // namespace cdp::adaptive
