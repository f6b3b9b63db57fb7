// Region features on small hand-made scenes whose regions and extents are
// known: coplanar patches merge, a step or a bend does not, and each patch
// gets its region's area, extents, height and orientation.
#include "findmug/features/region_features.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>

#include "findmug/common/error.hpp"
#include "findmug/features/features.hpp"
#include "findmug/frame/dataset.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr float kPi = 3.14159265358979f;

// A 40 x 10 grid of four 10-column patches in a row (0-1-2-3 adjacent).
// Patches 0..2 are a horizontal table top at 0.7 m (x = 0.025 m per column,
// y = 0.05 m per row; patch 2 is raised by `step_m`), patch 3 is a vertical
// wall rising from the top's far edge.
struct Scene {
  OrganizedCloud cloud;
  NormalImage normals;
  Oversegmentation seg;

  explicit Scene(float step_m) {
    const int w = 40, h = 10;
    cloud.width = normals.width = seg.width = w;
    cloud.height = normals.height = seg.height = h;
    cloud.points.resize(w * h);
    cloud.colors.resize(w * h, Rgb8{128, 128, 128});
    normals.normals.resize(w * h);
    seg.pixel_segment.resize(w * h);
    seg.segments.resize(4);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const int i = v * w + u;
        const int s = u / 10;
        seg.pixel_segment[i] = s;
        seg.segments[s].push_back(i);
        if (s < 3) {
          cloud.points[i] = {0.025f * u, 0.05f * v, 0.7f + (s == 2 ? step_m : 0.0f)};
          normals.normals[i] = {0, 0, 1};
        } else {
          cloud.points[i] = {0.75f, 0.05f * v, 0.7f + 0.05f * (u - 29)};
          normals.normals[i] = {-1, 0, 0};
        }
      }
    }
    seg.edges = {{0, 1}, {1, 2}, {2, 3}};
  }
  float feature(const RegionFeatures& r, int segment, int k) const {
    return r.values[segment * kRegionFeatureDim + k];
  }
};

TEST(RegionFeatures, CoplanarPatchesMergeAndGetTheirSurfacesFeatures) {
  const Scene scene(0.0f);
  const RegionFeatures r =
      computeRegionFeatures(scene.cloud, scene.normals, scene.seg, RegionConfig{});
  ASSERT_EQ(r.segment_region.size(), 4u);
  EXPECT_EQ(r.region_count, 2);
  EXPECT_EQ(r.segment_region[0], r.segment_region[1]);
  EXPECT_EQ(r.segment_region[1], r.segment_region[2]);
  EXPECT_NE(r.segment_region[2], r.segment_region[3]);
  ASSERT_EQ(r.values.size(), 4u * kRegionFeatureDim);

  // Table top: 30 columns x 10 rows of points, 0.025 m and 0.05 m apart.
  // sqrt(12 var) of n evenly spaced points with spacing d is d sqrt(n^2 - 1).
  const float major = 0.025f * std::sqrt(30.0f * 30.0f - 1.0f);
  const float minor = 0.05f * std::sqrt(10.0f * 10.0f - 1.0f);
  for (int s = 0; s < 3; ++s) {
    EXPECT_NEAR(scene.feature(r, s, 1), major, 1e-4f) << "segment " << s;
    EXPECT_NEAR(scene.feature(r, s, 2), minor, 1e-4f);
    EXPECT_NEAR(scene.feature(r, s, 0), major * minor, 1e-4f);
    EXPECT_NEAR(scene.feature(r, s, 3), 0.7f, 1e-5f);
    EXPECT_NEAR(scene.feature(r, s, 4), 0.7f, 1e-5f);
    EXPECT_NEAR(scene.feature(r, s, 5), 0.0f, 1e-5f);
  }
  // Wall: 10 x 10 points, 0.05 m apart both ways, rising from 0.75 m to 1.2 m.
  EXPECT_NEAR(scene.feature(r, 3, 5), kPi / 2, 1e-5f);
  EXPECT_NEAR(scene.feature(r, 3, 3), 0.7f + 0.05f * 5.5f, 1e-5f);
  EXPECT_NEAR(scene.feature(r, 3, 4), 0.7f + 0.05f * 10, 1e-5f);
  EXPECT_NEAR(scene.feature(r, 3, 1), 0.05f * std::sqrt(99.0f), 1e-4f);
}

TEST(RegionFeatures, AStepSplitsTheSurfaceUnlessTheToleranceAllowsIt) {
  const Scene scene(0.05f);  // patch 2 is 5 cm higher than patches 0 and 1
  RegionConfig config;       // 3 cm plane distance: a 5 cm step is another surface
  RegionFeatures r = computeRegionFeatures(scene.cloud, scene.normals, scene.seg, config);
  EXPECT_EQ(r.region_count, 3);
  EXPECT_EQ(r.segment_region[0], r.segment_region[1]);
  EXPECT_NE(r.segment_region[1], r.segment_region[2]);
  EXPECT_NEAR(scene.feature(r, 2, 3), 0.75f, 1e-5f);
  EXPECT_NEAR(scene.feature(r, 0, 1), 0.025f * std::sqrt(399.0f), 1e-4f);

  config.plane_distance_m = 0.06f;
  r = computeRegionFeatures(scene.cloud, scene.normals, scene.seg, config);
  EXPECT_EQ(r.region_count, 2);
  EXPECT_EQ(r.segment_region[1], r.segment_region[2]);
  EXPECT_NEAR(scene.feature(r, 0, 4), 0.75f, 1e-5f);  // the region's highest point

  // A 90 degree bend merges only when the angle limit allows it.
  config.normal_angle_deg = 89.0f;
  config.plane_distance_m = 1.0f;
  EXPECT_EQ(computeRegionFeatures(scene.cloud, scene.normals, scene.seg, config).region_count, 2);
  config.normal_angle_deg = 95.0f;
  EXPECT_EQ(computeRegionFeatures(scene.cloud, scene.normals, scene.seg, config).region_count, 1);
}

TEST(RegionFeatures, RefusesInconsistentInput) {
  Scene scene(0.0f);
  Oversegmentation bad = scene.seg;
  bad.edges.push_back({1, 7});
  EXPECT_THROW(computeRegionFeatures(scene.cloud, scene.normals, bad, RegionConfig{}), Error);
  NormalImage short_normals = scene.normals;
  short_normals.normals.pop_back();
  EXPECT_THROW(computeRegionFeatures(scene.cloud, short_normals, scene.seg, RegionConfig{}), Error);
  // A segment whose points are all invalid has no features.
  for (int i : scene.seg.segments[3]) scene.cloud.points[i].z() = std::nanf("");
  EXPECT_THROW(computeRegionFeatures(scene.cloud, scene.normals, scene.seg, RegionConfig{}), Error);
}

// The Segmenter computes region features from the 14-D features' moments
// (no second pass over the pixels). Both ways must give the same regions and
// the same values up to rounding.
void expectSameRegions(const RegionFeatures& from_pixels, const RegionFeatures& from_moments,
                       float tolerance) {
  ASSERT_EQ(from_moments.region_count, from_pixels.region_count);
  ASSERT_EQ(from_moments.segment_region, from_pixels.segment_region);
  ASSERT_EQ(from_moments.values.size(), from_pixels.values.size());
  for (std::size_t k = 0; k < from_pixels.values.size(); ++k) {
    const float a = from_pixels.values[k], b = from_moments.values[k];
    ASSERT_NEAR(b, a, tolerance * std::max(1.0f, std::abs(a)))
        << "segment " << k / kRegionFeatureDim << ", feature "
        << kRegionFeatureNames[k % kRegionFeatureDim];
  }
}

TEST(RegionFeatures, FromTheFeaturesMomentsEqualsFromThePoints) {
  for (const float step : {0.0f, 0.05f}) {
    for (const float shift : {0.0f, 60.0f}) {  // far from the origin: no cancellation
      SCOPED_TRACE("step " + std::to_string(step) + ", shift " + std::to_string(shift));
      Scene scene(step);
      for (auto& p : scene.cloud.points) p += Eigen::Vector3f(shift, -shift, 0.0f);
      const SegmentFeatures features = computeFeatures(scene.cloud, scene.normals, scene.seg);
      ASSERT_EQ(features.moments.size(), 4u);
      EXPECT_EQ(features.moments[0].count, 100.0);
      EXPECT_NEAR(features.moments[2].max_z, 0.7f + step, 1e-6f);
      for (const float distance : {0.03f, 0.06f}) {
        RegionConfig config;
        config.plane_distance_m = distance;
        const RegionFeatures from_pixels =
            computeRegionFeatures(scene.cloud, scene.normals, scene.seg, config);
        expectSameRegions(from_pixels, computeRegionFeatures(features, scene.seg, config), 1e-5f);
      }
      // The extents are those of the hand-made surface, whatever the shift.
      const RegionFeatures r = computeRegionFeatures(features, scene.seg, RegionConfig{});
      EXPECT_NEAR(scene.feature(r, 0, 1), 0.025f * std::sqrt(step == 0 ? 899.0f : 399.0f), 1e-4f);
    }
  }
}

TEST(RegionFeatures, FromMomentsRefusesFeaturesOfAnotherSegmentation) {
  const Scene scene(0.0f);
  SegmentFeatures features = computeFeatures(scene.cloud, scene.normals, scene.seg);
  features.moments.pop_back();
  EXPECT_THROW(computeRegionFeatures(features, scene.seg, RegionConfig{}), Error);
  features = computeFeatures(scene.cloud, scene.normals, scene.seg);
  features.moments[1].count = 0;
  EXPECT_THROW(computeRegionFeatures(features, scene.seg, RegionConfig{}), Error);
  features = computeFeatures(scene.cloud, scene.normals, scene.seg);
  features.moments[2].scatter(0, 0) = std::nan("");
  EXPECT_THROW(computeRegionFeatures(features, scene.seg, RegionConfig{}), Error);
}

TEST(RegionFeaturesNyu, FromTheFeaturesMomentsEqualsFromThePoints) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  const DatasetFolder dataset(dir.string());
  ASSERT_GE(dataset.size(), 10u);
  const auto oversegmenter = makeOversegmenter(OversegmentationConfig{});
  int regions = 0, merged = 0;
  for (std::size_t index = 0; index < dataset.size(); index += 5) {
    const LabeledFrame lf = dataset.load(index);
    SCOPED_TRACE(lf.name);
    const OrganizedCloud cloud = frameToCloud(lf.frame);
    const NormalImage normals = computeNormals(cloud, NormalConfig{});
    const Oversegmentation seg = oversegmenter->segment(cloud, normals);
    const SegmentFeatures features = computeFeatures(cloud, normals, seg);
    const RegionFeatures from_pixels = computeRegionFeatures(cloud, normals, seg, RegionConfig{});
    expectSameRegions(from_pixels, computeRegionFeatures(features, seg, RegionConfig{}), 1e-4f);
    regions += from_pixels.region_count;
    merged += static_cast<int>(seg.segments.size()) - from_pixels.region_count;
  }
  // Real frames do merge patches (else this compares nothing of the merging).
  EXPECT_GT(merged, regions / 4) << merged << " patches merged into " << regions << " regions";
}

}  // namespace
}  // namespace findmug
