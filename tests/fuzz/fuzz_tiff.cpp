// Fuzz target tiff: container (fuzz_support.hpp) of NAME_depth.tiff and NAME_rgb.tiff
// (tiff: replay source) -> readTiffFrame.
#include <cstddef>
#include <cstdint>
#include "findmug/common/error.hpp"
#include "findmug/io/pcl_frames.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto parts = findmug::fuzz::splitParts(data, size, 2);
    const auto depth = findmug::fuzz::scratchFile("frame_depth.tiff", parts[0]);
    const auto rgb = findmug::fuzz::scratchFile("frame_rgb.tiff", parts[1]);
    (void)findmug::io::readTiffFrame(depth, rgb, findmug::CameraIntrinsics{});
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
