// findmug/frame/frame.hpp — an RGB-D frame as it comes from a sensor or a dataset.
//
// Depth is registered to colour (same pixel grid), in millimetres, 0 = no
// measurement. Extrinsics are optional: a robot knows its camera mount, an
// NYU frame does not (then the ground plane is estimated instead).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug {

struct CameraIntrinsics {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
};

// Camera mount relative to the floor. Pitch is positive when the camera looks
// down; roll positive when the image turns clockwise. Height of the optical
// centre above the floor in metres.
struct CameraExtrinsics {
  double height_m = 0.0;
  double pitch_rad = 0.0;
  double roll_rad = 0.0;
};

struct RgbdFrame {
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> depth_mm;  // width*height, row-major, 0 = invalid
  std::vector<Rgb8> rgb;                // width*height, row-major
  CameraIntrinsics intrinsics;
  std::optional<CameraExtrinsics> extrinsics;
  // Optional gravity direction: unit "up" (against gravity) in camera
  // coordinates (x right, y down, z forward), e.g. from NYU's per-frame
  // rotations or an IMU. Used by ground.source=gravity; the floor height
  // is then found along it (see ground.hpp).
  std::optional<std::array<double, 3>> gravity_up;
  std::uint64_t utime = 0;  // capture time, microseconds, host clock
  std::int64_t seq = 0;     // sequence number from the source
  std::string source;       // where it came from (file name, device), for error messages
};

// Throws findmug::Error naming `frame.source` and the offending field when
// sizes disagree, dimensions are absurd, or intrinsics are not finite/positive.
void validateFrame(const RgbdFrame& frame);

}  // namespace findmug
