// Tests for features.hpp: CIELAB conversion, the 14-D patch descriptor on
// patches with known geometry, and the one-pass computeFeatures.
#include "findmug/features/features.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "features/features_internal.hpp"
#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr float kPi = static_cast<float>(M_PI);

struct Patch {
  std::vector<Eigen::Vector3f> points, normals;
  std::vector<Rgb8> colors;
  void add(const Eigen::Vector3f& p, const Eigen::Vector3f& n, Rgb8 c = {100, 150, 200}) {
    points.push_back(p);
    normals.push_back(n);
    colors.push_back(c);
  }
  FeatureVector features() const { return computePatchFeatures(points, normals, colors); }
};

TEST(RgbToLab, KnownColours) {
  const Eigen::Vector3f red = rgbToLab({255, 0, 0});
  EXPECT_NEAR(red.x(), 53.24f, 0.01f);
  EXPECT_NEAR(red.y(), 80.09f, 0.01f);
  EXPECT_NEAR(red.z(), 67.20f, 0.01f);
  const Eigen::Vector3f green = rgbToLab({0, 255, 0});
  EXPECT_NEAR(green.x(), 87.73f, 0.01f);
  EXPECT_NEAR(green.y(), -86.18f, 0.01f);
  EXPECT_NEAR(green.z(), 83.18f, 0.01f);
  const Eigen::Vector3f blue = rgbToLab({0, 0, 255});
  EXPECT_NEAR(blue.x(), 32.30f, 0.01f);
  EXPECT_NEAR(blue.y(), 79.19f, 0.01f);
  EXPECT_NEAR(blue.z(), -107.86f, 0.01f);
  const Eigen::Vector3f white = rgbToLab({255, 255, 255});
  EXPECT_NEAR(white.x(), 100.0f, 0.01f);
  EXPECT_NEAR(white.y(), 0.0f, 0.01f);
  EXPECT_NEAR(white.z(), 0.0f, 0.01f);
  EXPECT_TRUE(rgbToLab({0, 0, 0}).isZero(1e-4f));
  // A dark grey exercises the linear segments of both sRGB and CIELAB.
  const Eigen::Vector3f dark = rgbToLab({5, 5, 5});
  EXPECT_NEAR(dark.x(), 1.37f, 0.01f);
  EXPECT_NEAR(dark.y(), 0.0f, 0.01f);
}

TEST(PatchFeatures, FlatHorizontalPatchAtTableHeight) {
  Patch patch;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) patch.add({1.0f + 0.01f * i, -0.2f + 0.01f * j, 0.75f}, {0, 0, 1});
  const FeatureVector f = patch.features();
  EXPECT_NEAR(f[0], 0.0f, 1e-5f);  // pointness
  EXPECT_NEAR(f[1], 0.5f, 1e-4f);  // square: λ1 = λ2, so surfaceness = 1/2
  EXPECT_NEAR(f[2], 0.0f, 1e-4f);  // linearness
  EXPECT_GT(f[1], f[0]);
  EXPECT_GT(f[1], f[2]);
  EXPECT_NEAR(f[3], 0.75f, 1e-5f);
  EXPECT_NEAR(f[4], 0.75f, 1e-6f);
  EXPECT_NEAR(f[5], 0.75f, 1e-6f);
  EXPECT_NEAR(f[6], 0.0f, 1e-5f);  // up-facing
  EXPECT_NEAR(f[7], 0.0f, 1e-3f);  // all normals agree
  const Eigen::Vector3f lab = rgbToLab({100, 150, 200});
  EXPECT_NEAR(f[8], lab.x(), 0.01f);
  EXPECT_NEAR(f[9], lab.y(), 0.01f);
  EXPECT_NEAR(f[10], lab.z(), 0.01f);
  EXPECT_NEAR(f[11], 0.0f, 0.01f);
  EXPECT_NEAR(f[12], 0.0f, 0.01f);
  EXPECT_NEAR(f[13], 0.0f, 0.01f);
}

TEST(PatchFeatures, OblongPatchIsStillMoreSurfaceThanLine) {
  Patch patch;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 15; ++j) patch.add({0.01f * i, 0.01f * j, 0.4f}, {0, 0, 1});
  const FeatureVector f = patch.features();
  // λ ∝ (n² - 1): λ2/λ1 = 899/224.
  const float l1 = 224.0f, l2 = 899.0f;
  EXPECT_NEAR(f[1], l1 / (l1 + l2), 1e-3f);
  EXPECT_NEAR(f[2], (l2 - l1) / (l1 + l2), 1e-3f);
  EXPECT_NEAR(f[0] + f[1] + f[2], l2 / (l1 + l2), 1e-3f);  // the three sum to λ2/Σλ
}

TEST(PatchFeatures, VerticalWallAndCeiling) {
  Patch wall;
  for (int i = 0; i < 15; ++i)
    for (int k = 0; k < 15; ++k) wall.add({2.0f, 0.02f * i, 0.5f + 0.02f * k}, {-1, 0, 0});
  FeatureVector f = wall.features();
  EXPECT_NEAR(f[6], kPi / 2, 1e-5f);
  EXPECT_NEAR(f[7], 0.0f, 1e-3f);
  EXPECT_NEAR(f[4], 0.5f, 1e-6f);
  EXPECT_NEAR(f[5], 0.78f, 1e-5f);
  EXPECT_NEAR(f[3], 0.64f, 1e-5f);
  EXPECT_GT(f[1], 0.45f);

  Patch ceiling;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) ceiling.add({0.05f * i, 0.05f * j, 2.6f}, {0, 0, -1});
  f = ceiling.features();
  EXPECT_NEAR(f[6], kPi, 1e-5f);  // down-facing
  EXPECT_NEAR(f[3], 2.6f, 1e-5f);
}

TEST(PatchFeatures, LineOfPointsIsLinear) {
  Patch line;
  for (int i = 0; i < 50; ++i) line.add({0.3f, 0.1f + 0.01f * i, 0.2f + 0.01f * i}, {1, 0, 0});
  const FeatureVector f = line.features();
  EXPECT_NEAR(f[2], 1.0f, 1e-4f);
  EXPECT_NEAR(f[0], 0.0f, 1e-4f);
  EXPECT_NEAR(f[1], 0.0f, 1e-4f);
  EXPECT_NEAR(f[4], 0.2f, 1e-6f);
  EXPECT_NEAR(f[5], 0.69f, 1e-6f);
}

TEST(PatchFeatures, ScatteredBlobIsPointLike) {
  Patch blob;
  std::mt19937 rng(11);
  std::normal_distribution<float> g(0.0f, 0.05f);
  for (int i = 0; i < 2000; ++i) blob.add({g(rng), g(rng), 1.0f + g(rng)}, {0, 0, 1});
  const FeatureVector f = blob.features();
  EXPECT_NEAR(f[0], 1.0f / 3.0f, 0.03f);
  EXPECT_LT(f[1], 0.1f);
  EXPECT_LT(f[2], 0.1f);
}

TEST(PatchFeatures, NormalSpreadIsCircularStd) {
  // Half the normals up (θ = 0), half horizontal (θ = π/2): R = |1 + i|/2,
  // so the circular std is sqrt(-2 ln(1/√2)) = sqrt(ln 2); the mean normal
  // is 45 degrees from vertical.
  Patch corner;
  for (int i = 0; i < 100; ++i) {
    corner.add({0.01f * i, 0.0f, 0.0f}, {0, 0, 1});
    corner.add({0.01f * i, 0.1f, 0.0f}, {0, 1, 0});
  }
  FeatureVector f = corner.features();
  EXPECT_NEAR(f[7], std::sqrt(std::log(2.0f)), 1e-4f);
  EXPECT_NEAR(f[6], kPi / 4, 1e-4f);

  // Non-unit and NaN normals: the former are normalised, the latter skipped.
  Patch mixed;
  for (int i = 0; i < 10; ++i) mixed.add({0.01f * i, 0.0f, 1.0f}, {0, 0, 5});
  mixed.add({0.2f, 0.0f, 1.0f}, Eigen::Vector3f::Constant(std::nanf("")));
  f = mixed.features();
  EXPECT_NEAR(f[6], 0.0f, 1e-5f);
  EXPECT_NEAR(f[7], 0.0f, 1e-3f);
  EXPECT_NEAR(f[5], 1.0f, 1e-6f);
}

TEST(PatchFeatures, PatchWithoutNormalsUsesItsPrincipalAxes) {
  Patch wall;
  const Eigen::Vector3f nan = Eigen::Vector3f::Constant(std::nanf(""));
  for (int i = 0; i < 10; ++i)
    for (int k = 0; k < 10; ++k) wall.add({1.0f, 0.02f * i, 0.02f * k}, nan);
  const FeatureVector f = wall.features();
  EXPECT_NEAR(f[6], kPi / 2, 1e-4f);
  EXPECT_EQ(f[7], 0.0f);
}

TEST(PatchFeatures, ColourMeanAndSpread) {
  Patch p;
  for (int i = 0; i < 50; ++i) {
    p.add({0.01f * i, 0, 0}, {0, 0, 1}, Rgb8{0, 0, 0});
    p.add({0.01f * i, 0.01f, 0}, {0, 0, 1}, Rgb8{255, 255, 255});
  }
  const FeatureVector f = p.features();
  EXPECT_NEAR(f[8], 50.0f, 0.01f);
  EXPECT_NEAR(f[11], 50.0f, 0.01f);
  EXPECT_NEAR(f[9], 0.0f, 0.01f);
  EXPECT_NEAR(f[12], 0.0f, 0.01f);
}

TEST(PatchFeatures, TabulatedLabMatchesExactFormula) {
  // The descriptor converts colours through interpolated tables; they must
  // agree with rgbToLab to well below one CIELAB unit.
  std::mt19937 rng(2);
  for (int k = 0; k < 3000; ++k) {
    const Rgb8 c{static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()),
                 static_cast<std::uint8_t>(rng())};
    const FeatureVector f =
        computePatchFeatures({Eigen::Vector3f(0, 0, 1)}, {Eigen::Vector3f(0, 0, 1)}, {c});
    const Eigen::Vector3f lab = rgbToLab(c);
    ASSERT_NEAR(f[8], lab.x(), 0.01f) << int(c.r) << " " << int(c.g) << " " << int(c.b);
    ASSERT_NEAR(f[9], lab.y(), 0.01f);
    ASSERT_NEAR(f[10], lab.z(), 0.01f);
  }
}

TEST(PatchFeatures, RejectsMismatchedOrEmptyPatches) {
  EXPECT_THROW(computePatchFeatures({Eigen::Vector3f(0, 0, 1)}, {}, {Rgb8{}}), Error);
  EXPECT_THROW(computePatchFeatures({}, {}, {}), Error);
  const Eigen::Vector3f nan = Eigen::Vector3f::Constant(std::nanf(""));
  EXPECT_THROW(computePatchFeatures({nan}, {nan}, {Rgb8{}}), Error);
}

// A 40x30 organized cloud split into 4 quadrant segments, one left out (-1).
struct Grid {
  OrganizedCloud cloud;
  NormalImage normals;
  Oversegmentation seg;
};

Grid makeGrid() {
  Grid g;
  const int w = 40, h = 30;
  g.cloud.width = g.normals.width = g.seg.width = w;
  g.cloud.height = g.normals.height = g.seg.height = h;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> jitter(-0.01f, 0.01f);
  g.seg.segments.resize(3);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const int quadrant = (u >= w / 2) + 2 * (v >= h / 2);
      // Quadrants: 0 floor-like, 1 wall-like, 2 tilted, 3 no segment.
      Eigen::Vector3f p(0.02f * u, 0.02f * v, 0.0f), n(0, 0, 1);
      if (quadrant == 1) p.z() = 0.5f + 0.02f * v, n = Eigen::Vector3f(1, 0, 0);
      if (quadrant == 2)
        p.z() = 0.3f + 0.01f * u + jitter(rng), n = Eigen::Vector3f(-1, 0, 2).normalized();
      g.cloud.points.push_back(p);
      g.cloud.colors.push_back(
          Rgb8{static_cast<std::uint8_t>(u * 6), static_cast<std::uint8_t>(v * 8), 77});
      g.normals.normals.push_back(n);
      const int s = quadrant == 3 ? -1 : quadrant;
      g.seg.pixel_segment.push_back(s);
      if (s >= 0) g.seg.segments[s].push_back(v * w + u);
    }
  }
  // An invalid point inside segment 0 is ignored.
  g.cloud.points[0] = Eigen::Vector3f::Constant(std::nanf(""));
  return g;
}

TEST(ComputeFeatures, MatchesPerPatchFeaturesAndCentroids) {
  const Grid g = makeGrid();
  const SegmentFeatures sf = computeFeatures(g.cloud, g.normals, g.seg);
  ASSERT_EQ(sf.features.size(), 3u);
  ASSERT_EQ(sf.centroids.size(), 3u);
  for (std::size_t s = 0; s < 3; ++s) {
    Patch p;
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    int n = 0;
    for (int i : g.seg.segments[s]) {
      p.add(g.cloud.points[i], g.normals.normals[i], g.cloud.colors[i]);
      if (g.cloud.valid(i)) centroid += g.cloud.points[i], ++n;
    }
    const FeatureVector expected = p.features();
    for (int k = 0; k < kFeatureDim; ++k)
      EXPECT_NEAR(sf.features[s][k], expected[k], 1e-5f)
          << "segment " << s << " " << kFeatureNames[k];
    EXPECT_TRUE(sf.centroids[s].isApprox(centroid / n, 1e-5f));
  }
  EXPECT_NEAR(sf.features[0][6], 0.0f, 1e-5f);
  EXPECT_NEAR(sf.features[1][6], kPi / 2, 1e-5f);
  EXPECT_NEAR(sf.features[2][6], std::atan(0.5f), 1e-5f);
  EXPECT_NEAR(sf.features[1][4], 0.5f, 1e-5f);
  EXPECT_NEAR(sf.features[1][5], 0.5f + 0.02f * 14, 1e-5f);
}

TEST(ComputeFeatures, RejectsInconsistentInputs) {
  Grid g = makeGrid();
  Grid bad = g;
  bad.normals.normals.pop_back();
  EXPECT_THROW(computeFeatures(bad.cloud, bad.normals, bad.seg), Error);
  bad = g;
  bad.seg.pixel_segment[5] = 7;  // no such segment
  EXPECT_THROW(computeFeatures(bad.cloud, bad.normals, bad.seg), Error);
  bad = g;
  bad.cloud.colors.clear();
  EXPECT_THROW(computeFeatures(bad.cloud, bad.normals, bad.seg), Error);
  bad = g;
  for (int i : bad.seg.segments[1]) bad.cloud.points[i] = Eigen::Vector3f::Constant(std::nanf(""));
  EXPECT_THROW(computeFeatures(bad.cloud, bad.normals, bad.seg), Error);
}

// The same bits from the AVX2 feature pass as from the scalar one: every
// feature, centroid and moment, compared with memcmp. `what` names the input.
void expectSameFeaturesBothPaths(const OrganizedCloud& cloud, const NormalImage& normals,
                                 const Oversegmentation& seg, const std::string& what) {
  SegmentFeatures simd, portable;
  detail::computeFeaturesInto(cloud, normals, seg, simd, detail::FeatureSimd::Auto);
  detail::computeFeaturesInto(cloud, normals, seg, portable, detail::FeatureSimd::Off);
  ASSERT_EQ(simd.features.size(), portable.features.size()) << what;
  for (std::size_t s = 0; s < simd.features.size(); ++s) {
    EXPECT_EQ(0, std::memcmp(simd.features[s].data(), portable.features[s].data(),
                             sizeof(FeatureVector)))
        << what << ", segment " << s;
    EXPECT_EQ(0, std::memcmp(simd.centroids[s].data(), portable.centroids[s].data(),
                             sizeof(float) * 3))
        << what << ", segment " << s;
    const SegmentMoments& a = simd.moments[s];
    const SegmentMoments& b = portable.moments[s];
    EXPECT_TRUE(a.count == b.count &&
                !std::memcmp(a.mean.data(), b.mean.data(), sizeof(double) * 3) &&
                !std::memcmp(a.scatter.data(), b.scatter.data(), sizeof(double) * 9) &&
                !std::memcmp(a.normal_sum.data(), b.normal_sum.data(), sizeof(double) * 3) &&
                !std::memcmp(&a.max_z, &b.max_z, sizeof(float)))
        << what << ", segment " << s;
  }
}

// Real frames: NYU clouds oversegmented as the Segmenter does (camera frame:
// the pass does not care which frame it is).
TEST(FeatureSimd, NyuFramesMatchThePortableCodeBitForBit) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  const DatasetFolder dataset(root.string());
  ASSERT_GE(dataset.size(), 30u);
  OversegmentationConfig config;
  config.kind = OversegmenterKind::Organized;
  const auto oversegmenter = makeOversegmenter(config);
  for (std::size_t index = 0; index < dataset.size(); ++index) {
    const OrganizedCloud cloud = frameToCloud(dataset.load(index).frame);
    const NormalImage normals = computeNormals(cloud, NormalConfig{});
    const Oversegmentation seg = oversegmenter->segment(cloud, normals);
    ASSERT_GT(seg.segments.size(), 50u);
    expectSameFeaturesBothPaths(cloud, normals, seg, "NYU frame " + std::to_string(index));
  }
}

// The corners of the AVX2 pass: an image width that is not a multiple of
// eight (the last pixels of the image go one by one) and runs across its
// 256-pixel blocks; zero, NaN and infinite normals (no normal); black
// (CIELAB f at t <= 0), white and near-white colours (f at t >= 1, by the
// cube root); NaN points and pixels without a segment inside runs.
TEST(FeatureSimd, EdgeCasesMatchThePortableCodeBitForBit) {
  const int w = 203, h = 37;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> byte(0, 255);
  OrganizedCloud cloud;
  NormalImage normals;
  Oversegmentation seg;
  cloud.width = normals.width = seg.width = w;
  cloud.height = normals.height = seg.height = h;
  const int segments = 9;
  seg.segments.resize(segments);
  const float nan = std::nanf("");
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const int i = v * w + u;
      Eigen::Vector3f p(0.01f * u - 1.0f, 0.3f + 0.02f * v, 0.7f + 0.05f * unit(rng));
      Eigen::Vector3f n(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng));
      Rgb8 c{static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
             static_cast<std::uint8_t>(byte(rng))};
      switch (i % 13) {
        case 1: n = Eigen::Vector3f::Zero(); break;
        case 3: n = Eigen::Vector3f(nan, 0.0f, 1.0f); break;
        case 5: n = Eigen::Vector3f(std::numeric_limits<float>::infinity(), 0.0f, 0.0f); break;
        case 7: c = Rgb8{0, 0, 0}; break;
        case 8: c = Rgb8{255, 255, 255}; break;
        case 9: c = Rgb8{255, 254, 255}; break;
        case 11: p = Eigen::Vector3f::Constant(nan); break;
        default: break;
      }
      // Long runs (a third of the width) that cross block borders, and
      // some pixels with no segment.
      int s = (u / 68 + 3 * (v / 13)) % segments;
      if (i % 29 == 0) s = -1;
      cloud.points.push_back(p);
      cloud.colors.push_back(c);
      normals.normals.push_back(n);
      seg.pixel_segment.push_back(s);
      if (s >= 0) seg.segments[s].push_back(i);
    }
  }
  expectSameFeaturesBothPaths(cloud, normals, seg, "edge-case grid");
}

}  // namespace
}  // namespace findmug
