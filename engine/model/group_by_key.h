// group_by_key: items grouped by an integer key in one counting sort (the model's entries by world, the solver's
// actuators by dof, bodies by articulation).
#pragma once

#include <algorithm>

namespace novaphy {

// items [0, n) grouped by key (in [0, buckets); a negative key leaves the item out), a counting sort:
// items[start[k] .. start[k + 1]) are key k's, ascending; `next` is scratch of buckets + 1
template <typename Key>
void group_by_key(int n, int buckets, Key key, int* start, int* items, int* next) {
  std::fill_n(start, buckets + 1, 0);
  for (int i = 0; i < n; ++i)
    if (key(i) >= 0) ++start[key(i) + 1];
  for (int k = 0; k < buckets; ++k) start[k + 1] += start[k];
  std::copy_n(start, buckets, next);
  for (int i = 0; i < n; ++i)
    if (key(i) >= 0) items[next[key(i)]++] = i;
}

}  // namespace novaphy
