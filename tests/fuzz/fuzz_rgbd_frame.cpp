// Fuzz target rgbd_frame: rgbd_frame_t bytes (FINDMUG_RGBD) -> decodeRgbdFrame:
// the wire layout, sizes, intrinsics, utime, zlib/JPEG/PNG payloads and the frame checks.
#include <cstddef>
#include <cstdint>
#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeRgbdFrame(data, size, "FUZZ_RGBD");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
