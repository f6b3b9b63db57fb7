// Fuzz target object_model: a taught object's file (*.fmo in daemon.objects_dir,
// read by the daemon's ObjectLibrary) -> decodeObjectModel. What it accepts must
// encode back to the same bytes: the format has one spelling per model, so an
// accepted file that re-encodes differently was read wrongly.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "findmug/common/error.hpp"
#include "findmug/objects/object_model.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  findmug::ObjectModel model;
  try {
    model = findmug::decodeObjectModel(data, size, "fuzz.fmo");
  } catch (const findmug::Error&) {
    return 0;  // the expected answer to a bad input
  }
  const auto again = findmug::encodeObjectModel(model);
  if (again.size() != size || std::memcmp(again.data(), data, size) != 0) {
    std::fprintf(stderr, "object model accepted but re-encoded differently (%zu -> %zu bytes)\n",
                 size, again.size());
    std::abort();
  }
  return 0;
}
