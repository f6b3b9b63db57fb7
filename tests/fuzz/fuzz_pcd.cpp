// Fuzz target pcd: a PCD file (pcd: replay source) -> readPcdFrame.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "findmug/common/error.hpp"
#include "findmug/io/pcl_frames.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto path = findmug::fuzz::scratchFile(
        "frame.pcd", std::string_view(reinterpret_cast<const char*>(data), size));
    (void)findmug::io::readPcdFrame(path);
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
