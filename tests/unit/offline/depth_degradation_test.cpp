// The raw-depth model (depth_degradation.hpp): holes where a Kinect leaves
// them on hand-made frames, determinism by seed, the hole statistics, and the
// Segmenter on a degraded real NYU frame.
#include "findmug/offline/depth_degradation.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

// A wall 3 m away, mid grey, with a box 1 m away in front of it
// (columns 120..179, rows 60..139), and optionally a black patch on the wall
// (columns 220..279, rows 20..79).
constexpr int kW = 320, kH = 200;
constexpr int kBoxX0 = 120, kBoxX1 = 180, kBoxY0 = 60, kBoxY1 = 140;

RgbdFrame wallAndBox(bool black_patch) {
  RgbdFrame f;
  f.width = kW;
  f.height = kH;
  f.intrinsics = {290.0, 290.0, 159.5, 99.5};
  f.source = "hand-made wall and box";
  f.depth_mm.assign(static_cast<std::size_t>(kW) * kH, 3000);
  f.rgb.assign(f.depth_mm.size(), Rgb8{128, 128, 128});
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * kW + x;
      if (x >= kBoxX0 && x < kBoxX1 && y >= kBoxY0 && y < kBoxY1) f.depth_mm[i] = 1000;
      if (black_patch && x >= 220 && x < 280 && y >= 20 && y < 80) f.rgb[i] = Rgb8{5, 5, 5};
    }
  }
  return f;
}

double holeShare(const RgbdFrame& f, int x0, int x1, int y0, int y1) {
  int holes = 0, all = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      holes += f.depth_mm[static_cast<std::size_t>(y) * f.width + x] == 0;
      ++all;
    }
  return static_cast<double>(holes) / all;
}

TEST(DepthDegradation, ShadowLeftOfNearObjectEdgeBandAndNoHolesOnFlatFarFromEdges) {
  DepthDegradationConfig c;
  c.shadow_focal_px = 290.0f;
  DegradationReport report;
  const RgbdFrame out = degradeDepth(wallAndBox(false), c, 11, &report);
  EXPECT_FALSE(report.skipped);
  // The projector's shadow: f*b*(1/1 - 1/3) = 290 * 0.075 * 2/3 = 14.5 px
  // of wall left of the box, none right of it.
  EXPECT_GT(holeShare(out, kBoxX0 - 13, kBoxX0 - 3, kBoxY0 + 5, kBoxY1 - 5), 0.99);
  EXPECT_LT(holeShare(out, kBoxX0 - 30, kBoxX0 - 20, kBoxY0 + 5, kBoxY1 - 5), 0.1);
  EXPECT_GT(report.shadow, 10u * (kBoxY1 - kBoxY0));
  // A ragged band on the edge's other side (the box's right edge).
  const double band = holeShare(out, kBoxX1 - 2, kBoxX1 + 2, kBoxY0 + 5, kBoxY1 - 5);
  EXPECT_GT(band, 0.25);
  EXPECT_LT(band, 0.75);
  // Flat wall far from any edge: only the rare base dropouts.
  EXPECT_LT(holeShare(out, 230, 310, 150, 195), 0.05);
  c.base_hole_probability = 0.0f;
  const RgbdFrame clean_far = degradeDepth(wallAndBox(false), c, 11);
  EXPECT_EQ(holeShare(clean_far, 230, 310, 150, 195), 0.0);
  EXPECT_EQ(holeShare(clean_far, 0, kW, 0, 40), 0.0);
}

TEST(DepthDegradation, ShadowSideFollowsTheBaselineAndTurnsOff) {
  DepthDegradationConfig c;
  c.shadow_focal_px = 290.0f;
  c.edge_hole_probability = 0.0f;
  c.base_hole_probability = 0.0f;
  c.shadow_baseline_m = -0.075f;
  const RgbdFrame right = degradeDepth(wallAndBox(false), c, 3);
  EXPECT_GT(holeShare(right, kBoxX1 + 2, kBoxX1 + 12, kBoxY0 + 5, kBoxY1 - 5), 0.99);
  EXPECT_EQ(holeShare(right, kBoxX0 - 13, kBoxX0 - 3, kBoxY0 + 5, kBoxY1 - 5), 0.0);
  c.shadow_baseline_m = 0.0f;
  const RgbdFrame none = degradeDepth(wallAndBox(false), c, 3);
  EXPECT_EQ(holeShare(none, 0, kW, 0, kH), 0.0);
}

TEST(DepthDegradation, DarkSurfacesDropOutInBlobs) {
  DepthDegradationConfig c;
  c.base_hole_probability = 0.0f;
  const RgbdFrame out = degradeDepth(wallAndBox(true), c, 5);
  const double dark = holeShare(out, 225, 275, 25, 75);
  EXPECT_GT(dark, 0.3);
  EXPECT_LT(dark, 0.9);
  // In blobs: hole runs along rows are long, not single pixels.
  RgbdFrame patch = out;
  const HoleStatistics s = holeStatistics(patch, {225, 25, 275, 75, 5});
  EXPECT_GT(s.mean_run_px, 4.0);
  c.blob_size_px = 0.0f;  // independent pixels
  const HoleStatistics speckle =
      holeStatistics(degradeDepth(wallAndBox(true), c, 5), {225, 25, 275, 75, 5});
  EXPECT_LT(speckle.mean_run_px, s.mean_run_px / 2);
}

TEST(DepthDegradation, SameSeedSameFrameOtherSeedOtherFrame) {
  const DepthDegradationConfig c;
  const RgbdFrame in = wallAndBox(true);
  const RgbdFrame a = degradeDepth(in, c, 42), b = degradeDepth(in, c, 42),
                  other = degradeDepth(in, c, 43);
  EXPECT_EQ(a.depth_mm, b.depth_mm);
  EXPECT_NE(a.depth_mm, other.depth_mm);
  EXPECT_EQ(a.rgb, in.rgb);
  EXPECT_EQ(a.width, in.width);
}

TEST(DepthDegradation, DepthIsAnIntegerKinectDisparityNearTheTruth) {
  DepthDegradationConfig c;
  c.disparity_noise = 0.0f;
  const RgbdFrame out = degradeDepth(wallAndBox(false), c, 1);
  // 3 m: d = 1092.5 - 351.3 / 3 = 975.4, rounded to 975: 351.3 / 117.5 m.
  const std::uint16_t wall = out.depth_mm[static_cast<std::size_t>(190) * kW + 300];
  EXPECT_EQ(wall, static_cast<std::uint16_t>(std::lround(1000.0 * 351.3 / (1092.5 - 975))));
  c.disparity_noise = 1.0f;
  const RgbdFrame noisy = degradeDepth(wallAndBox(false), c, 1);
  int changed = 0, valid = 0;
  double worst = 0;
  for (int x = 200; x < 320; ++x) {
    const std::uint16_t d = noisy.depth_mm[static_cast<std::size_t>(190) * kW + x];
    if (d == 0) continue;
    ++valid;
    changed += d != wall;
    worst = std::max(worst, std::abs(d - 3000.0));
  }
  EXPECT_GT(changed, valid / 4);
  EXPECT_LT(worst, 200.0);  // a few disparity steps of 26 mm at 3 m
  c.quantise = false;
  c.disparity_noise = 0.0f;
  c.base_hole_probability = 0.0f;
  const RgbdFrame exact = degradeDepth(wallAndBox(false), c, 1);
  EXPECT_EQ(exact.depth_mm[static_cast<std::size_t>(190) * kW + 300], 3000);
}

TEST(DepthDegradation, RawFramesAreLeftAsTheyAre) {
  RgbdFrame raw = wallAndBox(false);
  for (std::size_t i = 0; i < raw.depth_mm.size(); i += 10) raw.depth_mm[i] = 0;  // 10 % holes
  DegradationReport report;
  const RgbdFrame out = degradeDepth(raw, DepthDegradationConfig{}, 9, &report);
  EXPECT_TRUE(report.skipped);
  EXPECT_EQ(out.depth_mm, raw.depth_mm);
  RgbdFrame broken = raw;
  broken.rgb.pop_back();
  EXPECT_THROW(degradeDepth(broken, DepthDegradationConfig{}, 9), Error);
}

TEST(DepthDegradation, HoleStatisticsBinsAndShadowSide) {
  RgbdFrame f = wallAndBox(true);
  // A shadow-like run left of the box (far side left), and one hole right of
  // it on the box's face (near on both sides: not counted).
  for (int y = 80; y < 90; ++y)
    for (int x = kBoxX0 - 6; x < kBoxX0; ++x) f.depth_mm[static_cast<std::size_t>(y) * kW + x] = 0;
  f.depth_mm[static_cast<std::size_t>(100) * kW + 150] = 0;
  const HoleStatistics s = holeStatistics(f);
  EXPECT_EQ(s.pixels, static_cast<std::size_t>(kW) * kH);
  EXPECT_EQ(s.holes, 61u);
  EXPECT_EQ(s.far_left_runs, 10u);
  EXPECT_EQ(s.far_right_runs, 0u);
  EXPECT_NEAR(s.mean_run_px, 61.0 / 11.0, 1e-9);
  // The holes are mid grey. Within 5 px of the run's pixels at columns
  // 115..119 lie both the wall (3 m) and the box (1 m): the largest spread;
  // column 114 sees only wall, the box's hole only box: no spread.
  EXPECT_EQ(s.by_brightness[2][1], 61u);
  EXPECT_EQ(s.by_brightness[0][1], 0u);
  EXPECT_EQ(s.by_spread[3][1], 50u);
  EXPECT_EQ(s.by_spread[0][1], 11u);
  EXPECT_EQ(s.isolated, 0u);
  std::size_t ranged = 0;
  for (const auto& bin : s.by_range) ranged += bin[1];
  EXPECT_EQ(ranged, 61u);
  EXPECT_EQ(s.by_range[3][1], 0u);  // nothing beyond 4.5 m
  EXPECT_THROW(holeStatistics(f, {0, 0, kW + 1, kH, 5}), Error);
}

// A degraded real NYU frame through the whole Segmenter: finite features, and
// labels only where there is depth.
TEST(DepthDegradation, PipelineOnADegradedRealFrame) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  DatasetOptions options;
  options.nyu_rotations_file = rotations.string();
  const DatasetFolder folder(nyu.string(), options);
  const LabeledFrame clean = folder.load(0);  // 0001: filled depth
  SegmenterConfig config;
  config.oversegmentation.kind = OversegmenterKind::Organized;
  config.ground.source = GroundSource::Gravity;
  config.regions.enabled = true;
  config.scene.enabled = true;
  DegradationReport report;
  const RgbdFrame raw = degradeDepth(clean.frame, DepthDegradationConfig{}, 2, &report);
  ASSERT_FALSE(report.skipped);
  const double holes = static_cast<double>(report.holes_added) / report.valid_before;
  EXPECT_GT(holes, 0.03);
  EXPECT_LT(holes, 0.6);

  const Segmenter untrained(config, nullptr);
  const LabeledFrames one{"0001", 1, [&](std::size_t) { return clean; }};
  ExtractionReport extraction;
  const auto samples = extractSamples(one, untrained, extraction);
  ASSERT_EQ(samples.size(), 1u);
  config.forest.num_trees = 2;
  config.forest.max_depth = 8;
  auto forest = std::make_shared<RandomForest>(trainModel({&samples[0]}, config));
  forest->setExtractionSettings(extractionSettings(config));
  const Segmenter segmenter(config, forest);

  const LabelledFrame out = segmenter.process(raw);
  ASSERT_FALSE(out.features.features.empty());
  for (const auto& row : out.features.features)
    for (float v : row) ASSERT_TRUE(std::isfinite(v));
  for (float v : out.features.regions) ASSERT_TRUE(std::isfinite(v));
  for (float v : out.features.scene) ASSERT_TRUE(std::isfinite(v));
  ASSERT_EQ(out.labels.labels.size(), raw.depth_mm.size());
  // The holes take their neighbours' labels (labels.fill_holes) with no
  // confidence of their own; almost all are near enough to a labelled pixel.
  std::size_t labelled = 0, holes_total = 0, holes_filled = 0;
  for (std::size_t i = 0; i < raw.depth_mm.size(); ++i) {
    if (raw.depth_mm[i] == 0) {
      ASSERT_EQ(out.labels.confidence[i], 0.0f) << i;
      ++holes_total;
      holes_filled += out.labels.labels[i] < kNumLabels;
    }
    labelled += out.labels.labels[i] < kNumLabels;
  }
  EXPECT_GT(labelled, raw.depth_mm.size() / 3);
  EXPECT_GT(holes_filled, holes_total * 9 / 10);
  SegmenterConfig no_fill = config;
  no_fill.label_holes.enabled = false;
  const LabelledFrame unfilled = Segmenter(no_fill, forest).process(raw);
  for (std::size_t i = 0; i < raw.depth_mm.size(); ++i) {
    if (raw.depth_mm[i] == 0) {
      ASSERT_EQ(unfilled.labels.labels[i], kVoidLabel) << i;
    }
  }
  for (float c : out.labels.confidence) ASSERT_TRUE(std::isfinite(c));
}

// training.degraded_copies: each training frame brings raw-like copies of
// itself (as variants, which join every training set it is in), each
// through the whole geometry, with its own seed.
TEST(DepthDegradation, TrainingCopiesJoinTheTrainingSet) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  DatasetOptions options;
  options.nyu_rotations_file = rotations.string();
  const DatasetFolder folder(nyu.string(), options);
  const LabeledFrame clean = folder.load(1);  // 0002
  const LabeledFrames one{"0002", 1, [&](std::size_t) { return clean; }};
  Config config;
  applyOverride(config, "oversegmentation.method=organized");
  applyOverride(config, "ground.source=gravity");
  applyOverride(config, "training.degraded_copies=2");
  applyOverride(config, "training.degraded_seed=9");
  EXPECT_EQ(config.offline.training.degraded_seed, 9u);
  EXPECT_THROW(applyOverride(config, "degrade.edge_hole_probability=1.5"), Error);
  EXPECT_THROW(applyOverride(config, "training.degraded_copies=9"), Error);
  ExtractionReport report;
  const auto samples =
      extractTrainingSamples(one, Segmenter(config.segmenter, nullptr), config.offline, report);
  ASSERT_EQ(samples.size(), 1u);
  ASSERT_EQ(samples[0].variants.size(), 2u);
  std::size_t clean_pixels = 0;
  for (auto p : samples[0].segment_pixels) clean_pixels += p;
  for (const FrameSample& copy : samples[0].variants) {
    EXPECT_EQ(copy.source_index, 0u);
    EXPECT_NE(copy.name.find("~raw"), std::string::npos);
    std::size_t pixels = 0;
    for (auto p : copy.segment_pixels) pixels += p;
    EXPECT_LT(pixels, clean_pixels * 0.97);  // the holes are in no segment
    EXPECT_GT(pixels, clean_pixels * 0.4);
  }
  EXPECT_NE(samples[0].variants[0].pixel_segment, samples[0].variants[1].pixel_segment);
  const TrainingSet set = makeTrainingSet({&samples[0]});
  std::size_t rows = 0;
  for (const FrameSample* s : {&samples[0], &samples[0].variants[0], &samples[0].variants[1]})
    for (auto y : s->segment_labels) rows += y < kNumLabels;
  EXPECT_EQ(set.labels.size(), rows);
}

}  // namespace
}  // namespace findmug
