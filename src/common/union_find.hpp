// union_find.hpp — disjoint sets over 0..n-1 in a plain parent vector, for the
// stages that group patches (region features, object candidates).
//
// The lower index becomes the root when two sets join, so a set's root (and
// the order of the groups numbered by root) does not depend on the order the
// joins came in. Path halving keeps the trees flat.
#pragma once

#include <algorithm>
#include <vector>

namespace findmug::detail {

inline int unionFindRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

inline void unionFindJoin(std::vector<int>& parent, int a, int b) {
  const int ra = unionFindRoot(parent, a), rb = unionFindRoot(parent, b);
  if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
}

}  // namespace findmug::detail
