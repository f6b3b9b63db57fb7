#include "findmug/frame/frame.hpp"

#include <cmath>
#include <sstream>

#include "findmug/common/error.hpp"

namespace findmug {

namespace {
// A Kinect-class sensor is 640x480; allow up to 4K so that other sensors and
// synthetic frames fit, but refuse sizes that can only come from corruption.
constexpr int kMaxFrameDimension = 4096;

std::string where(const RgbdFrame& frame) {
  return frame.source.empty() ? std::string("frame ") + std::to_string(frame.seq) : frame.source;
}
}  // namespace

void validateFrame(const RgbdFrame& frame) {
  if (frame.width <= 0 || frame.height <= 0 || frame.width > kMaxFrameDimension ||
      frame.height > kMaxFrameDimension) {
    std::ostringstream msg;
    msg << where(frame) << ": absurd frame size " << frame.width << "x" << frame.height
        << " (expected 1.." << kMaxFrameDimension << " per side)";
    throw Error(msg.str());
  }
  const auto pixels = static_cast<std::size_t>(frame.width) * frame.height;
  if (frame.depth_mm.size() != pixels) {
    throw Error(where(frame) + ": depth has " + std::to_string(frame.depth_mm.size()) +
                " pixels, expected " + std::to_string(pixels) + " (" +
                std::to_string(frame.width) + "x" + std::to_string(frame.height) + ")");
  }
  if (frame.rgb.size() != pixels) {
    throw Error(where(frame) + ": colour has " + std::to_string(frame.rgb.size()) +
                " pixels, expected " + std::to_string(pixels));
  }
  const auto& k = frame.intrinsics;
  if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy)) ||
      k.fx <= 0 || k.fy <= 0) {
    std::ostringstream msg;
    msg << where(frame) << ": invalid intrinsics fx=" << k.fx << " fy=" << k.fy << " cx=" << k.cx
        << " cy=" << k.cy;
    throw Error(msg.str());
  }
  if (frame.extrinsics) {
    const auto& e = *frame.extrinsics;
    if (!std::isfinite(e.height_m) || e.height_m <= 0.0 || e.height_m > 5.0 ||
        !std::isfinite(e.pitch_rad) || std::abs(e.pitch_rad) > M_PI / 2 ||
        !std::isfinite(e.roll_rad) || std::abs(e.roll_rad) > M_PI / 2) {
      std::ostringstream msg;
      msg << where(frame) << ": invalid extrinsics height_m=" << e.height_m
          << " pitch_rad=" << e.pitch_rad << " roll_rad=" << e.roll_rad;
      throw Error(msg.str());
    }
  }
}

}  // namespace findmug
