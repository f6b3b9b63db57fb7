#include "findmug/offline/layout_counts.hpp"

#include <string>

#include "findmug/common/error.hpp"
#include "findmug/offline/cv_folds.hpp"

namespace findmug {

void addLayoutPairs(const Image<std::uint8_t>& labels, int offset, LayoutCounts& counts) {
  if (offset < 1) throw Error("layout counts: offset " + std::to_string(offset) + " (expected >= 1)");
  if (labels.width < 0 || labels.height < 0 ||
      labels.pixels.size() != static_cast<std::size_t>(labels.width) * labels.height)
    throw Error("layout counts: label map of " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " holds " + std::to_string(labels.pixels.size()) +
                " pixels");
  const int w = labels.width, h = labels.height;
  auto at = [&](int x, int y) { return labels.pixels[static_cast<std::size_t>(y) * w + x]; };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::uint8_t a = at(x, y);
      if (a >= kNumLabels) continue;
      if (y + offset < h) {
        const std::uint8_t below = at(x, y + offset);
        if (below < kNumLabels && below != a) counts.vertical[a * kNumLabels + below] += 1;
      }
      if (x + offset < w) {
        const std::uint8_t right = at(x + offset, y);
        if (right < kNumLabels && right != a) {
          counts.horizontal[a * kNumLabels + right] += 1;
          counts.horizontal[right * kNumLabels + a] += 1;
        }
      }
    }
  }
  ++counts.frames;
}

std::vector<long> indicesOutsideScenes(const std::vector<long>& candidates,
                                       const std::vector<long>& evaluation,
                                       const std::vector<long>& test_indices) {
  const std::vector<std::string> evaluation_scenes = nyuSplitRunScenes(evaluation, test_indices);
  const std::set<std::string> excluded(evaluation_scenes.begin(), evaluation_scenes.end());
  const std::vector<std::string> scenes = nyuSplitRunScenes(candidates, test_indices);
  std::vector<long> out;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (!excluded.count(scenes[i])) out.push_back(candidates[i]);
  return out;
}

}  // namespace findmug
