// Fuzz target robot_pose: robot_pose_t bytes (FINDMUG_ROBOT_POSE) -> decodeRobotPose.
#include <cstddef>
#include <cstdint>
#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeRobotPose(data, size, "FUZZ_POSE");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
