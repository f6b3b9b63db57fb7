// Fuzz target pclzf: container (fuzz_support.hpp) of NAME_depth.pclzf, NAME_rgb.pclzf and
// NAME.xml (pclzf: replay source) -> readPclzfFrame.
#include <cstddef>
#include <cstdint>
#include "findmug/common/error.hpp"
#include "findmug/io/pcl_frames.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto parts = findmug::fuzz::splitParts(data, size, 3);
    const auto depth = findmug::fuzz::scratchFile("frame_depth.pclzf", parts[0]);
    const auto rgb = findmug::fuzz::scratchFile("frame_rgb.pclzf", parts[1]);
    const auto xml = findmug::fuzz::scratchFile("frame.xml", parts[2]);
    (void)findmug::io::readPclzfFrame(depth, rgb, xml);
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
