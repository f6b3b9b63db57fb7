// Fuzz target label_csv: a label-mapping CSV (findmug-train --mapping) -> parseLabelMapping.
#include <cstddef>
#include <cstdint>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)findmug::parseLabelMapping(std::string(reinterpret_cast<const char*>(data), size),
                                     "fuzz.csv");
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
