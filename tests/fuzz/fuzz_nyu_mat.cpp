// Fuzz target nyu_mat: container (fuzz_support.hpp) of the NYU-894 -> 40 CSV and
// nyu_depth_v2_labeled.mat (HDF5) -> NyuMatFile, loading the first and last frames.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/offline/nyu_mat.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    // The container: the NYU-894 -> 40 CSV, then the .mat (HDF5) file.
    const auto parts = findmug::fuzz::splitParts(data, size, 2);
    const auto csv = findmug::fuzz::scratchFile("nyu894_to_40.csv", parts[0]);
    const auto mat = findmug::fuzz::scratchFile("labeled.mat", parts[1]);
    findmug::NyuMatFile file(mat, csv);
    // The first and the last frame: the hyperslab offsets at both ends (a
    // frame can be 1280x1024, so not every one: each input must stay < 1 s).
    if (file.size() > 0) (void)file.load(0);
    if (file.size() > 1) (void)file.load(file.size() - 1);
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
