// floor_to_int.hpp — internal to findmug_core: floor of a float as an int,
// for the grid and voxel cells of per-point passes.
#pragma once

namespace findmug::detail {

// floor(v) as an int, for |v| < 2^31: truncate, then step down where the
// truncation rounded up (negative non-integers). The same value as
// static_cast<int>(std::floor(v)), without the rounding-mode sequence that
// std::floor compiles to on x86-64 before SSE4.1 (several times the cost of
// the rest of a cell computation); and plain enough for the compiler to
// vectorise.
inline int floorToInt(float v) {
  const int t = static_cast<int>(v);
  return t - (static_cast<float>(t) > v ? 1 : 0);
}

}  // namespace findmug::detail
