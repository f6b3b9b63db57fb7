// Fuzz target png: a PNG -> decodePngRgb (LCM colour), readPng16 (depth), readPng8 (labels).
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const std::vector<std::uint8_t> bytes(data, data + size);
    try {
      (void)findmug::decodePngRgb(bytes, "fuzz png");
    } catch (const findmug::Error&) {
    }
    const auto path = findmug::fuzz::scratchFile(
        "image.png", std::string_view(reinterpret_cast<const char*>(data), size));
    try {
      (void)findmug::readPng16(path);  // depth images of dataset folders
    } catch (const findmug::Error&) {
    }
    (void)findmug::readPng8(path);  // label images
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
