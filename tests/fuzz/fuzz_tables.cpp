// Fuzz target tables: tables_t bytes (FINDMUG_TABLES / FINDMUG_TABLE_MAP) -> decodeTables,
// as the navigation client decodes them.
#include <cstddef>
#include <cstdint>
#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::io::decodeTables(data, size, "FUZZ_TABLES");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
