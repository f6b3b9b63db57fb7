// Fuzz target command: command_t bytes (FINDMUG_COMMAND, requests to findmugd) -> decodeCommand.
#include <cstddef>
#include <cstdint>
#include "findmug/io/lcm_codec.hpp"
#include "findmug/common/error.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeCommand(data, size, "FUZZ_COMMAND");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
