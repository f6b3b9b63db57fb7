// lcm_codec_checks.hpp — the field checks every LCM decoder of findmug_io shares
// (internal to io/src): a bad field is reported as "CHANNEL: TYPE.FIELD: what is wrong".
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>

#include "findmug/common/error.hpp"

namespace findmug::io::detail {

// Same limit as validateFrame(): a Kinect is 640x480; anything beyond 4096 a
// side can only come from a corrupt message, and must be refused before
// width*height sizes an allocation.
inline constexpr std::int32_t kMaxSide = 4096;

inline std::string field(std::string_view channel, std::string_view type, std::string_view name) {
  return std::string(channel) + ": " + std::string(type) + "." + std::string(name);
}

inline void checkDimensions(std::int32_t width, std::int32_t height, std::string_view channel,
                            std::string_view type) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide) {
    throw Error(field(channel, type, "width/height") + ": absurd image size " +
                std::to_string(width) + "x" + std::to_string(height) + " (expected 1.." +
                std::to_string(kMaxSide) + " per side)");
  }
}

inline void checkArraySize(std::int32_t declared, std::size_t actual, std::string_view channel,
                           std::string_view type, std::string_view name) {
  if (declared < 0 || static_cast<std::size_t>(declared) != actual) {
    throw Error(field(channel, type, name) + ": size field says " + std::to_string(declared) +
                " but the array holds " + std::to_string(actual));
  }
}

inline bool finite(double v) { return std::isfinite(v); }

inline void checkFinite(std::initializer_list<double> values, const std::string& where) {
  for (double v : values) {
    if (!finite(v)) throw Error(where + ": non-finite value");
  }
}

}  // namespace findmug::io::detail
