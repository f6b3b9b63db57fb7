// Fuzz target objects: objects_t bytes (FINDMUG_OBJECTS) -> decodeObjects, as the
// navigation client and any other listener decode them.
#include <cstddef>
#include <cstdint>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeObjects(data, size, "FUZZ_OBJECTS");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
