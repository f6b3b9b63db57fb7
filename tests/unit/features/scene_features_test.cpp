// Scene features on a small hand-made scene whose answers are known: a wall
// in two patches, a cabinet (front, top) in front of a wall, a table top
// with floor below it. Heights sit in the middle of the 0.1 m bins so that
// each point's bin is unambiguous.
#include "findmug/features/scene_features.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "findmug/common/error.hpp"
#include "common/point_extent.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

enum Patch { kWallLow, kWallHigh, kWallBehindCabinet, kCabinetFront, kCabinetTop, kTableTop, kFloor };

// 40 x 30 grid; image columns 0-9, 10-19, 20-29, 30-39 are four bands of
// 10 px. The camera is at (0, 0, 1.2) in the ground frame, looking along +x.
struct Scene {
  OrganizedCloud cloud;
  Oversegmentation seg;
  SegmentFeatures features;
  const Eigen::Vector3f camera{0.0f, 0.0f, 1.2f};
  static constexpr int kWidth = 40, kHeight = 30;

  Scene() {
    cloud.width = seg.width = kWidth;
    cloud.height = seg.height = kHeight;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    cloud.points.assign(kWidth * kHeight, Eigen::Vector3f(nan, nan, nan));
    cloud.colors.assign(kWidth * kHeight, Rgb8{128, 128, 128});
    seg.pixel_segment.assign(kWidth * kHeight, -1);
    seg.segments.resize(7);
    // Band 0: a wall at x = 3 m from the floor to 2.45 m, in two patches.
    fill(kWallLow, 0, 15, 25, [](int c, int r) { return P(3.0f, 0.05f * c, 0.1f * (r - 15) + 0.05f); });
    fill(kWallHigh, 0, 0, 15, [](int c, int r) { return P(3.0f, 0.05f * c, 1.05f + 0.1f * (14 - r)); });
    // Band 1: a cabinet front at x = 2.5 m up to 0.95 m, the wall above it at x = 3 m.
    fill(kWallBehindCabinet, 10, 0, 15,
         [](int, int r) { return P(3.0f, 0.5f, 1.05f + 0.1f * (14 - r)); });
    fill(kCabinetFront, 10, 15, 25, [](int, int r) { return P(2.5f, 0.5f, 0.1f * (r - 15) + 0.05f); });
    // Band 2: the cabinet's top at 1.02 m, 2.5..2.68 m from the camera.
    fill(kCabinetTop, 20, 0, 10, [](int c, int) { return P(2.5f + 0.02f * (c - 20), 0.5f, 1.02f); });
    // Band 3: a table top at 0.72 m with the floor visible below it.
    fill(kTableTop, 30, 0, 5, [](int c, int) { return P(1.5f + 0.02f * (c - 30), -1.0f, 0.72f); });
    fill(kFloor, 30, 20, 25, [](int c, int) { return P(1.5f + 0.02f * (c - 30), -1.0f, 0.02f); });
    // Base features the scene features read: min/max height and centroid.
    for (const auto& pixels : seg.segments) {
      FeatureVector f{};
      Eigen::Vector3f sum = Eigen::Vector3f::Zero();
      f[4] = std::numeric_limits<float>::infinity();
      f[5] = -f[4];
      for (int i : pixels) {
        sum += cloud.points[i];
        f[4] = std::min(f[4], cloud.points[i].z());
        f[5] = std::max(f[5], cloud.points[i].z());
      }
      features.centroids.push_back(sum / static_cast<float>(pixels.size()));
      f[3] = features.centroids.back().z();
      features.features.push_back(f);
    }
  }
  static Eigen::Vector3f P(float x, float y, float z) { return {x, y, z}; }
  template <typename F>
  void fill(Patch s, int col0, int row0, int row1, F point) {
    for (int r = row0; r < row1; ++r) {
      for (int c = col0; c < col0 + 10; ++c) {
        const int i = r * kWidth + c;
        cloud.points[i] = point(c, r);
        seg.pixel_segment[i] = s;
        seg.segments[s].push_back(i);
      }
    }
  }
  float horizontal(const Eigen::Vector3f& p) const {
    return std::hypot(p.x() - camera.x(), p.y() - camera.y());
  }
};

SceneConfig config() {
  SceneConfig c;
  c.enabled = true;
  c.cell_m = 0.1f;
  c.band_px = 10;
  return c;
}

TEST(SceneFeatures, KnownAnswersOnAHandMadeScene) {
  const Scene scene;
  const std::vector<float> v =
      computeSceneFeatures(scene.cloud, scene.seg, scene.features, scene.camera, config());
  ASSERT_EQ(v.size(), 7u * kSceneFeatureDim);
  auto at = [&](Patch s, int k) { return v[s * kSceneFeatureDim + k]; };

  // scene_top_gap: one frame top for all patches, so gaps differ exactly by
  // the patches' heights; the walls reach the top, furniture does not.
  EXPECT_NEAR(at(kTableTop, 0) - at(kCabinetTop, 0), 1.02f - 0.72f, 1e-5f);
  EXPECT_LT(at(kWallHigh, 0), 0.1f);
  EXPECT_GT(at(kTableTop, 0), 1.5f);

  // column_depth_ratio: the walls are the farthest in their bands; the
  // cabinet front stands 0.5 m in front of the wall above it.
  EXPECT_NEAR(at(kWallBehindCabinet, 1), 1.0f, 1e-6f);
  EXPECT_NEAR(at(kCabinetFront, 1),
              scene.horizontal({2.5f, 0.5f, 0}) / scene.horizontal({3.0f, 0.5f, 0}), 1e-5f);
  const Eigen::Vector3f table_centroid = scene.features.centroids[kTableTop];
  EXPECT_NEAR(at(kTableTop, 1),
              scene.horizontal(table_centroid) / scene.horizontal({1.68f, -1.0f, 0}), 1e-5f);

  // fill_below: the cabinet's top has its front below it in every bin from
  // the floor up; the table top only the floor's bin of the 7 below 0.72 m.
  EXPECT_FLOAT_EQ(at(kCabinetTop, 2), 1.0f);
  EXPECT_FLOAT_EQ(at(kTableTop, 2), 1.0f / 7.0f);
  EXPECT_FLOAT_EQ(at(kFloor, 2), 0.0f);  // nothing lies below the floor

  // fill_above: the wall continues above its lower patch up to the top;
  // nothing stands on the table or the cabinet.
  EXPECT_FLOAT_EQ(at(kWallLow, 3), 1.0f);
  EXPECT_FLOAT_EQ(at(kTableTop, 3), 0.0f);
  EXPECT_FLOAT_EQ(at(kCabinetTop, 3), 0.0f);
  // The floor under the table: the table top is 1 of the 24 bins above it.
  EXPECT_GT(at(kFloor, 3), 0.0f);
  EXPECT_LT(at(kFloor, 3), 0.2f);
}

TEST(SceneFeatures, BandWidthDecidesWhatIsBehind) {
  // With one band over the whole image, the farthest point is the wall at
  // x = 3 m, y = 0.5 m (or 0.45 m): the table is then far from the back.
  const Scene scene;
  SceneConfig wide = config();
  wide.band_px = 40;
  const std::vector<float> v =
      computeSceneFeatures(scene.cloud, scene.seg, scene.features, scene.camera, wide);
  const float far = scene.horizontal({3.0f, 0.5f, 0});
  EXPECT_NEAR(v[kTableTop * kSceneFeatureDim + 1],
              scene.horizontal(scene.features.centroids[kTableTop]) / far, 1e-5f);
}

TEST(SceneFeatures, MismatchedInputsAreErrors) {
  Scene scene;
  scene.features.features.pop_back();
  try {
    computeSceneFeatures(scene.cloud, scene.seg, scene.features, scene.camera, config());
    ADD_FAILURE() << "accepted 6 feature rows for 7 segments";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("7 segments"));
  }
  Scene small;
  small.cloud.points.pop_back();
  EXPECT_THROW(computeSceneFeatures(small.cloud, small.seg, small.features, small.camera, config()),
               Error);
}

// The scene grid's extent (detail::pointExtent, SSE2) against running
// std::min / std::max over the points with a finite z, bit for bit: random
// points with NaN and infinite z (skipped), NaN and infinite x or y (a NaN
// never replaces an extreme), and signed zeros (the first of equal values
// stays, as std::min keeps it). And no point at all: infinite extremes.
TEST(PointExtent, MatchesRunningStdMinAndMax) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> coordinate(-8.0f, 8.0f);
  const float specials[] = {nan, inf, -inf, 0.0f, -0.0f};
  for (int trial = 0; trial < 300; ++trial) {
    const int n = std::uniform_int_distribution<int>(0, 40)(rng);
    std::vector<Eigen::Vector3f> points(static_cast<std::size_t>(n));
    for (auto& p : points) {
      for (int axis = 0; axis < 3; ++axis) {
        p[axis] = std::uniform_int_distribution<int>(0, 5)(rng) == 0
                      ? specials[std::uniform_int_distribution<int>(0, 4)(rng)]
                      : coordinate(rng);
      }
    }
    float expected[5] = {inf, inf, -inf, -inf, -inf};  // min x, min y, max x, max y, max z
    for (const auto& p : points) {
      if (!std::isfinite(p.z())) continue;
      expected[0] = std::min(expected[0], p.x());
      expected[1] = std::min(expected[1], p.y());
      expected[2] = std::max(expected[2], p.x());
      expected[3] = std::max(expected[3], p.y());
      expected[4] = std::max(expected[4], p.z());
    }
    const detail::PointExtent e = detail::pointExtent(points);
    const float got[5] = {e.min_x, e.min_y, e.max_x, e.max_y, e.max_z};
    for (int k = 0; k < 5; ++k) {
      EXPECT_EQ(std::memcmp(&got[k], &expected[k], sizeof(float)), 0)
          << "trial " << trial << ", extreme " << k << ": " << got[k] << " vs " << expected[k];
    }
  }
}

}  // namespace
}  // namespace findmug
