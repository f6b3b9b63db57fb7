// Fuzz target semantic_map_file: a saved semantic map (daemon.semantic_map_file) ->
// SemanticMap::loadBytes, then the map's tables (what the daemon does next with it).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/map/semantic_map.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  findmug::SemanticMap map;
  try {
    map.loadBytes(std::vector<std::uint8_t>(data, data + size), "fuzz.map");
  } catch (const findmug::Error&) {
    return 0;  // the expected answer to a bad input
  }
  try {
    (void)map.tables();
  } catch (const findmug::Error&) {
    // Refused geometry is an answer too; anything else is a finding.
  }
  return 0;
}
