// label_holes.cpp — unlabelled pixels (no depth) take the label of the pixels around them.
#include "findmug/labels/label_holes.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"

namespace findmug {

namespace {

// The labelled pixels bounding a run of unlabelled ones (indices into the
// image, -1 where the run touches the border).
struct RunEnds {
  std::ptrdiff_t before = -1, after = -1;
};

class RunFiller {
 public:
  RunFiller(const std::vector<std::uint16_t>& depth_mm, LabelImage& labels)
      : depth_mm_(depth_mm), labels_(labels) {}

  // Fills the run of `length` pixels starting at `first`, `step` apart.
  // Returns how many pixels it filled (0 when the run is left void).
  std::size_t fill(std::ptrdiff_t first, std::ptrdiff_t step, int length, RunEnds ends) {
    const bool has_before = ends.before >= 0;
    const bool has_after = ends.after >= 0;
    if (!has_before && !has_after) return 0;
    const std::uint8_t before = has_before ? labels_.labels[ends.before] : kVoidLabel;
    const std::uint8_t after = has_after ? labels_.labels[ends.after] : kVoidLabel;
    if (!has_before || !has_after || before == after) {
      paint(first, step, 0, length, has_before ? before : after);
      return static_cast<std::size_t>(length);
    }
    const std::uint16_t z_before = depth_mm_[static_cast<std::size_t>(ends.before)];
    const std::uint16_t z_after = depth_mm_[static_cast<std::size_t>(ends.after)];
    if (z_before > 0 && z_after > 0) {
      // A shadow or an edge band: the surface behind.
      paint(first, step, 0, length, z_before >= z_after ? before : after);
    } else {
      // A side was itself filled (no depth to compare): the nearer side.
      const int half = length / 2;
      paint(first, step, 0, half, before);
      paint(first, step, half, length, after);
    }
    return static_cast<std::size_t>(length);
  }

 private:
  void paint(std::ptrdiff_t first, std::ptrdiff_t step, int from, int to, std::uint8_t label) {
    for (int k = from; k < to; ++k) {
      const std::ptrdiff_t i = first + step * k;
      labels_.labels[i] = label;
      labels_.confidence[i] = 0.0f;
    }
  }

  const std::vector<std::uint16_t>& depth_mm_;
  LabelImage& labels_;
};

// Returns how many pixels it filled; `row_left_void[y]` is 1 where row y
// keeps a void pixel.
std::size_t fillRows(const LabelHoleFillConfig& config, RunFiller& filler, LabelImage& labels,
                     std::vector<std::uint8_t>& row_left_void) {
  std::size_t filled = 0;
  const int width = labels.width;
  row_left_void.assign(static_cast<std::size_t>(labels.height), 0);
  for (int y = 0; y < labels.height; ++y) {
    const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(y) * width;
    const std::uint8_t* label_row = labels.labels.data() + row;
    for (int x = 0; x < width; ++x) {
      // Most pixels are labelled: skip to the next void one (vectorised).
      const void* next =
          std::memchr(label_row + x, kVoidLabel, static_cast<std::size_t>(width - x));
      if (!next) break;
      x = static_cast<int>(static_cast<const std::uint8_t*>(next) - label_row);
      int end = x + 1;
      while (end < width && label_row[end] == kVoidLabel) ++end;
      const int length = end - x;
      // A run across the whole row has no side to take a label from.
      const std::size_t n =
          length <= config.max_run_px
              ? filler.fill(row + x, 1, length,
                            {x > 0 ? row + x - 1 : -1, end < width ? row + end : -1})
              : 0;
      filled += n;
      if (n < static_cast<std::size_t>(length)) row_left_void[static_cast<std::size_t>(y)] = 1;
      x = end;
    }
  }
  return filled;
}

// Row-major over the image, one open run per column, so that the pass reads
// the image in memory order; rows without a void pixel are skipped while no
// run is open.
std::size_t fillColumns(const LabelHoleFillConfig& config, RunFiller& filler, LabelImage& labels,
                        const std::vector<std::uint8_t>& row_left_void,
                        std::vector<int>& run_start) {
  std::size_t filled = 0;
  const int width = labels.width;
  run_start.assign(static_cast<std::size_t>(width), -1);
  int open = 0;
  const auto close = [&](int x, int start, int end) {
    const int length = end - start;
    if (length > config.max_run_px) return;
    const std::ptrdiff_t first = static_cast<std::ptrdiff_t>(start) * width + x;
    const std::ptrdiff_t before = start > 0 ? first - width : -1;
    const std::ptrdiff_t after =
        end < labels.height ? static_cast<std::ptrdiff_t>(end) * width + x : -1;
    filled += filler.fill(first, width, length, {before, after});
  };
  for (int y = 0; y < labels.height; ++y) {
    if (open == 0 && !row_left_void[static_cast<std::size_t>(y)]) continue;
    const std::uint8_t* label_row = labels.labels.data() + static_cast<std::ptrdiff_t>(y) * width;
    for (int x = 0; x < width; ++x) {
      int& start = run_start[static_cast<std::size_t>(x)];
      if (label_row[x] == kVoidLabel) {
        if (start < 0) {
          start = y;
          ++open;
        }
      } else if (start >= 0) {
        close(x, start, y);
        start = -1;
        --open;
      }
    }
  }
  for (int x = 0; x < width && open > 0; ++x) {
    if (run_start[static_cast<std::size_t>(x)] >= 0) {
      close(x, run_start[static_cast<std::size_t>(x)], labels.height);
    }
  }
  return filled;
}

}  // namespace

std::size_t fillLabelHoles(const std::vector<std::uint16_t>& depth_mm,
                           const LabelHoleFillConfig& config, LabelImage& labels) {
  if (!config.enabled) return 0;
  const std::size_t pixels =
      static_cast<std::size_t>(std::max(labels.width, 0)) * std::max(labels.height, 0);
  if (labels.labels.size() != pixels || labels.confidence.size() != pixels ||
      depth_mm.size() != pixels) {
    throw Error("fillLabelHoles: label image is " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " with " + std::to_string(labels.labels.size()) +
                " labels and " + std::to_string(labels.confidence.size()) +
                " confidences, depth has " + std::to_string(depth_mm.size()) + " pixels");
  }
  if (config.max_run_px < 1) {
    throw Error("fillLabelHoles: max_run_px is " + std::to_string(config.max_run_px) +
                " (must be at least 1)");
  }
  RunFiller filler(depth_mm, labels);
  // Per-thread working memory: a warm stream of frames allocates nothing here.
  thread_local std::vector<std::uint8_t> row_left_void;
  thread_local std::vector<int> run_start;
  std::size_t filled = fillRows(config, filler, labels, row_left_void);
  if (std::find(row_left_void.begin(), row_left_void.end(), 1) != row_left_void.end())
    filled += fillColumns(config, filler, labels, row_left_void, run_start);
  return filled;
}

}  // namespace findmug
