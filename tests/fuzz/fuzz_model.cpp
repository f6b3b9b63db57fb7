// Fuzz target model: a model file (.fmf) -> RandomForest::load, then predict on a few inputs.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "findmug/common/error.hpp"
#include "findmug/features/features.hpp"
#include "findmug/learner/forest.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto path = findmug::fuzz::scratchFile(
        "model.fmf", std::string_view(reinterpret_cast<const char*>(data), size));
    const auto forest = findmug::RandomForest::load(path);
    // A loaded model must be safe to run: walk every tree with a few inputs.
    if (!forest.empty()) {
      findmug::FeatureVector x{};
      for (float v : {-1e30f, 0.0f, 0.5f, 1e30f}) {
        x.fill(v);
        (void)forest.predict(x);
      }
    }
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
