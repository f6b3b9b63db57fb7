// Fuzz target semantic_map: semantic_map_t bytes (FINDMUG_SEMANTIC_MAP) -> decodeSemanticMap.
#include <cstddef>
#include <cstdint>

#include "findmug/common/error.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeSemanticMap(data, size, "FUZZ_SEMANTIC_MAP");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
