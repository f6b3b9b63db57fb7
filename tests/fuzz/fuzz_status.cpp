// Fuzz target status: status_t bytes (FINDMUG_STATUS) -> decodeMessage<status_t>, as findmug-spy reads them.
#include <cstddef>
#include <cstdint>
#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeMessage<findmug_lcm::status_t>(data, size, "FUZZ_STATUS");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
