// Fuzz target label_image: label_image_t bytes (FINDMUG_LABELS) -> decodeLabelImage,
// as the label viewer, findmug-web and the navigation client decode them, then the colour
// image it may carry (decodeLabelImageColor, as the label viewer does).
#include <cstddef>
#include <cstdint>
#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto message = findmug::io::decodeLabelImage(data, size, "FUZZ_LABELS");
    (void)findmug::io::decodeLabelImageColor(message, "FUZZ_LABELS");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
