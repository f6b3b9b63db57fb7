// Fuzz target find_result: find_result_t bytes (FINDMUG_FIND_RESULT) -> decodeFindResult, as
// findmug-nav-client --find and any other client decode the daemon's answer to "find NAME".
#include <cstddef>
#include <cstdint>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeFindResult(data, size, "FUZZ_FIND_RESULT");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
