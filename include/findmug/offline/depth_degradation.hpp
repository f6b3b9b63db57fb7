// findmug/offline/depth_degradation.hpp — hole-filled depth made to look like a live Kinect's raw depth.
//
// NYU's labelled frames hold inpainted depth with no holes; a robot's
// structured-light camera gives raw depth: holes in the projector's shadow
// beside near objects, a ragged band at depth edges, dropouts on dark,
// saturated or far surfaces (in blobs, not single pixels), and depth that is
// the inverse of an integer disparity with noise (steps and noise growing
// with the square of the range). degradeDepth() applies such a model to a
// frame, deterministically for a seed, for training augmentation
// (training.degraded_copies) and for evaluation on raw-like copies
// (findmug-eval --degrade). holeStatistics() measures where a frame's holes
// are, the same way on real raw frames and on degraded ones, to calibrate
// the model against the real thing (findmug-depth-holes).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "findmug/frame/frame.hpp"
#include "findmug/settings/offline_settings.hpp"

namespace findmug {


// Where the model's holes came from, for reports and tests.
struct DegradationReport {
  bool skipped = false;  // the input was raw already (max_input_hole_fraction)
  std::size_t valid_before = 0, holes_added = 0;
  std::size_t shadow = 0, edge = 0, dropout = 0;  // by cause (a pixel counts once, first cause)
};

// A copy of `frame` with raw-like depth. Deterministic: the same frame,
// config and seed give the same output; another seed other holes and noise.
// Throws findmug::Error (validateFrame) on an inconsistent frame.
RgbdFrame degradeDepth(const RgbdFrame& frame, const DepthDegradationConfig& config,
                       std::uint64_t seed, DegradationReport* report = nullptr);

// Hole statistics of a frame within a rectangle (the NYU projection mask on
// NYU frames): the share of zero-depth pixels overall and by cause-related
// context, computed only from what a raw frame shows (so that real raw and
// degraded frames are measured alike).
struct HoleStatistics {
  static constexpr int kBrightnessBins = 5;  // grey 0-40, 40-80, 80-140, 140-220, 220-255
  static constexpr int kSpreadBins = 4;  // local relative depth spread <2 %, 2-10, 10-30, >=30 %
  static constexpr int kRangeBins = 4;   // local depth <2, 2-3, 3-4.5, >=4.5 m
  std::size_t pixels = 0, holes = 0;
  // Per bin: pixels, holes. Spread and range bins count only pixels with a
  // measured neighbour within the window; `isolated` counts the rest.
  std::array<std::array<std::size_t, 2>, kBrightnessBins> by_brightness{};
  std::array<std::array<std::size_t, 2>, kSpreadBins> by_spread{};
  std::array<std::array<std::size_t, 2>, kRangeBins> by_range{};
  std::size_t isolated = 0;
  // Hole runs along rows bounded by measured pixels whose depths differ by
  // more than 10 %: how many have the far side on the left (a shadow of the
  // Kinect's kind), how many on the right; and the mean length of all hole
  // runs in rows (px), a measure of how blobby the holes are.
  std::size_t far_left_runs = 0, far_right_runs = 0;
  double mean_run_px = 0.0;

  double holeShare() const { return pixels ? static_cast<double>(holes) / pixels : 0.0; }
};
struct StatisticsWindow {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // [x0, x1) x [y0, y1); all 0: the whole frame
  int radius_px = 5;                   // the neighbourhood of spread and range
};
HoleStatistics holeStatistics(const RgbdFrame& frame, const StatisticsWindow& window = {});
// The bins as text ("grey 0-40"), for reports.
std::string brightnessBinName(int bin);
std::string spreadBinName(int bin);
std::string rangeBinName(int bin);

}  // namespace findmug
