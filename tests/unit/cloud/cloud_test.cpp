// Tests for cloud.hpp: pinhole back-projection, organized normals, transforms.
#include "findmug/cloud/cloud.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "cloud/cloud_internal.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr float kPi = static_cast<float>(M_PI);

RgbdFrame blankFrame(int w, int h, CameraIntrinsics k) {
  RgbdFrame f;
  f.width = w;
  f.height = h;
  f.intrinsics = k;
  f.depth_mm.assign(static_cast<std::size_t>(w) * h, 0);
  f.rgb.assign(static_cast<std::size_t>(w) * h, Rgb8{10, 20, 30});
  f.source = "synthetic";
  return f;
}

// Depth (mm, rounded like a sensor) of the plane n.p + d = 0 seen through
// pixel (u, v); 0 when the ray misses it (behind the camera).
std::uint16_t planeDepthMm(const CameraIntrinsics& k, int u, int v, const Eigen::Vector3f& n,
                           float d) {
  const Eigen::Vector3f ray(static_cast<float>((u - k.cx) / k.fx),
                            static_cast<float>((v - k.cy) / k.fy), 1.0f);
  const float z = -d / n.dot(ray);
  if (!(z > 0.0f)) return 0;
  return static_cast<std::uint16_t>(std::lround(z * 1000.0f));
}

TEST(FrameToCloud, BackProjectsThroughPinholeModel) {
  const CameraIntrinsics k{100.0, 110.0, 31.5, 23.5};
  RgbdFrame f = blankFrame(64, 48, k);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) f.depth_mm[v * 64 + u] = static_cast<std::uint16_t>(1000 + 10 * u);
  f.rgb[5 * 64 + 7] = Rgb8{200, 100, 50};

  const OrganizedCloud c = frameToCloud(f);
  ASSERT_EQ(c.width, 64);
  ASSERT_EQ(c.height, 48);
  ASSERT_EQ(c.points.size(), 64u * 48u);
  ASSERT_EQ(c.colors.size(), 64u * 48u);
  for (int v : {0, 5, 23, 47}) {
    for (int u : {0, 7, 31, 63}) {
      const float z = (1000 + 10 * u) / 1000.0f;
      const Eigen::Vector3f& p = c.points[v * 64 + u];
      EXPECT_NEAR(p.z(), z, 1e-6f);
      EXPECT_NEAR(p.x(), (u - 31.5f) * z / 100.0f, 1e-5f) << u << "," << v;
      EXPECT_NEAR(p.y(), (v - 23.5f) * z / 110.0f, 1e-5f) << u << "," << v;
    }
  }
  EXPECT_EQ(c.colors[5 * 64 + 7], (Rgb8{200, 100, 50}));
  // x right, y down: the top-left pixel is up and to the left of the axis.
  EXPECT_LT(c.points[0].x(), 0.0f);
  EXPECT_LT(c.points[0].y(), 0.0f);
}

TEST(FrameToCloud, ZeroAndTooFarDepthBecomeNaN) {
  RgbdFrame f = blankFrame(8, 4, {});
  std::fill(f.depth_mm.begin(), f.depth_mm.end(), 2000);
  f.depth_mm[3] = 0;
  f.depth_mm[4] = 10001;  // beyond the default 10 m
  f.depth_mm[5] = 4001;
  const OrganizedCloud c = frameToCloud(f);
  EXPECT_FALSE(c.valid(3));
  EXPECT_TRUE(std::isnan(c.points[3].x()) && std::isnan(c.points[3].y()));
  EXPECT_FALSE(c.valid(4));
  EXPECT_TRUE(c.valid(5));
  EXPECT_TRUE(c.valid(0));
  const OrganizedCloud near = frameToCloud(f, 4.0f);
  EXPECT_FALSE(near.valid(5));
  EXPECT_TRUE(near.valid(0));
}

TEST(FrameToCloud, RejectsBadFrameAndBadMaxDepth) {
  RgbdFrame f = blankFrame(8, 4, {});
  f.depth_mm.pop_back();
  EXPECT_THROW(frameToCloud(f), Error);
  RgbdFrame g = blankFrame(8, 4, {});
  EXPECT_THROW(frameToCloud(g, 0.0f), Error);
  EXPECT_THROW(frameToCloud(g, std::nanf("")), Error);
  g.intrinsics.fx = -1;
  EXPECT_THROW(frameToCloud(g), Error);
}

TEST(ComputeNormals, TiltedPlaneGivesItsNormalFacingTheCamera) {
  const CameraIntrinsics k{525.0, 525.0, 159.5, 119.5};
  RgbdFrame f = blankFrame(320, 240, k);
  // A plane tilted 30 degrees about x and 20 about y, 2 m in front.
  const Eigen::Vector3f n_true =
      (Eigen::AngleAxisf(0.35f, Eigen::Vector3f::UnitY()) *
       Eigen::AngleAxisf(kPi / 6, Eigen::Vector3f::UnitX()) * Eigen::Vector3f(0, 0, -1))
          .normalized();
  const float d = 2.0f;  // n.p + d = 0 and n faces the camera: n.(0,0,2) = -2 roughly
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) f.depth_mm[v * 320 + u] = planeDepthMm(k, u, v, n_true, d);
  const OrganizedCloud c = frameToCloud(f);
  const NormalImage normals = computeNormals(c, NormalConfig{});
  ASSERT_EQ(normals.normals.size(), c.points.size());
  int checked = 0;
  for (int v = 10; v < 230; v += 7) {
    for (int u = 10; u < 310; u += 7) {
      const Eigen::Vector3f& n = normals.normals[v * 320 + u];
      ASSERT_TRUE(n.allFinite()) << u << "," << v;
      EXPECT_NEAR(n.norm(), 1.0f, 1e-4f);
      // Millimetre depth rounding at ~2 m: allow 3 degrees.
      EXPECT_GT(n.dot(n_true), std::cos(3.0f * kPi / 180))
          << u << "," << v << " n=" << n.transpose();
      EXPECT_LT(n.dot(c.points[v * 320 + u]), 0.0f);  // faces the camera
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(ComputeNormals, DepthStepDoesNotBendNormalsAndHolesStayNaN) {
  const CameraIntrinsics k{525.0, 525.0, 79.5, 59.5};
  RgbdFrame f = blankFrame(160, 120, k);
  // Left half: fronto-parallel wall at 1 m. Right half: floor-like plane
  // much further away. A normal that mixed them would be far off.
  const Eigen::Vector3f floor_n = Eigen::Vector3f(0, -1, -0.5f).normalized();
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u)
      f.depth_mm[v * 160 + u] = u < 80 ? 1000 : planeDepthMm(k, u, v, floor_n, 0.9f);
  // A single valid pixel in a hole has no neighbours: no normal.
  for (int v = 90; v < 110; ++v)
    for (int u = 10; u < 30; ++u) f.depth_mm[v * 160 + u] = 0;
  f.depth_mm[100 * 160 + 20] = 1000;
  const OrganizedCloud c = frameToCloud(f);
  ASSERT_GT(c.points[60 * 160 + 100].z(), 1.5f);  // the far plane really is far
  const NormalImage normals = computeNormals(c, NormalConfig{});
  for (int v = 10; v < 80; v += 3) {
    for (int u : {74, 76, 77}) {  // 3+ pixels left of the step
      const Eigen::Vector3f& n = normals.normals[v * 160 + u];
      ASSERT_TRUE(n.allFinite());
      EXPECT_GT(n.dot(Eigen::Vector3f(0, 0, -1)), std::cos(1.0f * kPi / 180)) << u << "," << v;
    }
    for (int u : {83, 85}) {  // right of the step
      const Eigen::Vector3f& n = normals.normals[v * 160 + u];
      ASSERT_TRUE(n.allFinite());
      EXPECT_GT(n.dot(floor_n), std::cos(3.0f * kPi / 180)) << u << "," << v;
    }
  }
  EXPECT_FALSE(normals.normals[100 * 160 + 20].allFinite());
  EXPECT_FALSE(normals.normals[95 * 160 + 15].allFinite());  // no point at all
}

TEST(ComputeNormals, RejectsBadConfigAndShape) {
  OrganizedCloud c;
  c.width = 4;
  c.height = 4;
  c.points.assign(16, Eigen::Vector3f(0, 0, 1));
  NormalConfig bad;
  bad.window_radius_px = 0;
  EXPECT_THROW(computeNormals(c, bad), Error);
  bad = NormalConfig{};
  bad.max_depth_jump_m = -1.0f;
  EXPECT_THROW(computeNormals(c, bad), Error);
  c.points.pop_back();
  EXPECT_THROW(computeNormals(c, NormalConfig{}), Error);
}

TEST(TransformCloud, MovesValidPointsAndKeepsNaN) {
  OrganizedCloud c;
  c.width = 2;
  c.height = 1;
  c.points = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f::Constant(std::nanf(""))};
  c.colors = {Rgb8{1, 2, 3}, Rgb8{4, 5, 6}};
  Eigen::Isometry3f t = Eigen::Isometry3f::Identity();
  t.linear() = Eigen::AngleAxisf(kPi / 2, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3f(10, 0, 0);
  const OrganizedCloud out = transformCloud(c, t);
  EXPECT_TRUE(out.points[0].isApprox(Eigen::Vector3f(8, 1, 3), 1e-5f)) << out.points[0].transpose();
  EXPECT_FALSE(out.valid(1));
  EXPECT_EQ(out.colors, c.colors);
  EXPECT_EQ(out.width, 2);

  NormalImage n;
  n.width = 2;
  n.height = 1;
  n.normals = {Eigen::Vector3f(1, 0, 0), Eigen::Vector3f::Constant(std::nanf(""))};
  const NormalImage r = rotateNormals(n, t.linear());
  EXPECT_TRUE(r.normals[0].isApprox(Eigen::Vector3f(0, 1, 0), 1e-5f));
  EXPECT_FALSE(r.normals[1].allFinite());
}

// The raw normals have an AVX2 path (taken where the CPU has AVX2, as on
// every machine this project runs on) beside the scalar code. Both must give
// the same normals to the bit, or labels would depend on the CPU.
void expectSameNormalsBitForBit(const OrganizedCloud& cloud, const NormalConfig& config,
                                const std::string& what) {
  NormalImage simd, scalar;
  detail::computeNormals(cloud, config, simd, detail::CloudSimd::Auto);
  detail::computeNormals(cloud, config, scalar, detail::CloudSimd::Off);
  ASSERT_EQ(simd.normals.size(), scalar.normals.size()) << what;
  std::size_t finite = 0;
  for (std::size_t i = 0; i < scalar.normals.size(); ++i) {
    ASSERT_EQ(std::memcmp(simd.normals[i].data(), scalar.normals[i].data(), sizeof(float) * 3), 0)
        << what << ": pixel " << i << " (" << i % cloud.width << ", " << i / cloud.width
        << "): SIMD " << simd.normals[i].transpose() << ", scalar "
        << scalar.normals[i].transpose();
    finite += scalar.normals[i].allFinite();
  }
  // Else the comparison says nothing.
  EXPECT_GT(finite, scalar.normals.size() / 3) << what;
}

TEST(NormalsSimd, MatchesTheScalarCodeBitForBitOnRandomSurfacesWithHoles) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  // Widths that are and are not multiples of 8, narrower than 2r + 8, and
  // every window radius up to 9 (the SIMD path runs between r and w - r).
  for (const int w : {5, 17, 24, 37, 64, 101}) {
    for (int r = 1; r <= 9; r += 2) {
      const int h = 23;
      OrganizedCloud cloud;
      cloud.width = w;
      cloud.height = h;
      const float tilt = unit(rng) - 0.5f;
      for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
          // A wavy, tilted surface 1-4 m away with depth steps and holes.
          float z = 1.0f + 0.002f * unit(rng) + tilt * u * 0.005f + 0.02f * std::sin(0.3f * u) +
                    (u > w / 2 ? 0.3f : 0.0f) + 0.004f * v;
          if (unit(rng) < 0.08f) z = std::nanf("");
          cloud.points.emplace_back((u - w / 2) * 0.002f * z, (v - h / 2) * 0.002f * z, z);
        }
      }
      NormalConfig config;
      config.window_radius_px = r;
      expectSameNormalsBitForBit(cloud, config, "w " + std::to_string(w) + ", r " + std::to_string(r));
      config.smoothing_radius_px = 0;  // the raw normals themselves
      expectSameNormalsBitForBit(cloud, config,
                                 "raw, w " + std::to_string(w) + ", r " + std::to_string(r));
    }
  }
}

TEST(NormalsSimdNyu, MatchesTheScalarCodeBitForBit) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  const DatasetFolder dataset(dir.string());
  ASSERT_GE(dataset.size(), 10u);
  NormalConfig raw;
  raw.smoothing_radius_px = 0;
  for (std::size_t index = 0; index < dataset.size(); index += 6) {
    const LabeledFrame lf = dataset.load(index);
    const OrganizedCloud cloud = frameToCloud(lf.frame);
    expectSameNormalsBitForBit(cloud, NormalConfig{}, lf.name);
    expectSameNormalsBitForBit(cloud, raw, lf.name + " (raw)");
  }
}


// The ground-frame transforms of points and normals, AVX2 against Eigen's
// portable expressions, bit for bit: random rotations and translations,
// vectors of every magnitude, NaN and infinite coordinates, and every tail
// length (counts 0-40).
// frameToCloud's AVX2 rows give the scalar code's points to the bit: random
// depths with zeros, the sensor's largest value and depths next to the
// max_depth_m limit (whole and fractional millimetre limits), image widths
// that leave every tail length after the eight-pixel steps, odd intrinsics.
TEST(FrameToCloudSimd, MatchesTheScalarCodeBitForBit) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> depth(1, 65535);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 60; ++trial) {
    const int width = 1 + trial % 29, height = 1 + trial % 5;
    const CameraIntrinsics k{300.0 + 500.0 * unit(rng), 300.0 + 500.0 * unit(rng),
                             width * unit(rng), height * unit(rng)};
    RgbdFrame f = blankFrame(width, height, k);
    const float max_depth_m = trial % 3 == 0 ? 4.0f : 0.5f + 8.0f * static_cast<float>(unit(rng));
    const int limit = static_cast<int>(max_depth_m * 1000.0f);
    for (std::size_t i = 0; i < f.depth_mm.size(); ++i) {
      int d = depth(rng);
      switch (i % 6) {
        case 0: d = 0; break;
        case 1: d = std::clamp(limit + static_cast<int>(i / 6 % 3) - 1, 0, 65535); break;
        case 2: d = 65535; break;
        default: break;
      }
      f.depth_mm[i] = static_cast<std::uint16_t>(d);
    }
    OrganizedCloud simd, scalar;
    detail::frameToCloud(f, max_depth_m, simd, detail::CloudSimd::Auto);
    detail::frameToCloud(f, max_depth_m, scalar, detail::CloudSimd::Off);
    ASSERT_EQ(simd.points.size(), scalar.points.size());
    EXPECT_EQ(0, std::memcmp(simd.points.data(), scalar.points.data(),
                             simd.points.size() * sizeof(Eigen::Vector3f)))
        << "trial " << trial << ", " << width << "x" << height << ", max " << max_depth_m;
    EXPECT_EQ(simd.colors, scalar.colors);
  }
}

TEST(TransformSimd, MatchesEigenBitForBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_real_distribution<float> exponent(-8.0f, 8.0f);
  const float nan = std::nanf(""), inf = std::numeric_limits<float>::infinity();
  std::size_t compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Isometry3f transform = Eigen::Isometry3f::Identity();
    transform.linear() =
        Eigen::AngleAxisf(3.0f * unit(rng), Eigen::Vector3f(unit(rng), unit(rng), unit(rng)).normalized())
            .toRotationMatrix();
    transform.translation() = Eigen::Vector3f(unit(rng), unit(rng), 2.0f * unit(rng));
    const int count = trial % 41;
    OrganizedCloud cloud;
    cloud.width = count;
    cloud.height = 1;
    NormalImage normals;
    normals.width = count;
    normals.height = 1;
    for (int k = 0; k < count; ++k) {
      Eigen::Vector3f p;
      for (int c = 0; c < 3; ++c) p[c] = unit(rng) * std::exp2(exponent(rng));
      if (k % 7 == 3) p[k % 3] = nan;
      if (k % 11 == 5) p[(k + 1) % 3] = -inf;
      cloud.points.push_back(p);
      cloud.colors.push_back(Rgb8{static_cast<std::uint8_t>(k), 0, 0});
      normals.normals.push_back(p.allFinite() ? Eigen::Vector3f(p.normalized()) : p);
    }
    OrganizedCloud simd_cloud, portable_cloud;
    detail::transformCloud(cloud, transform, simd_cloud, detail::CloudSimd::Auto);
    detail::transformCloud(cloud, transform, portable_cloud, detail::CloudSimd::Off);
    NormalImage simd_normals, portable_normals;
    detail::rotateNormals(normals, transform.linear(), simd_normals, detail::CloudSimd::Auto);
    detail::rotateNormals(normals, transform.linear(), portable_normals, detail::CloudSimd::Off);
    ASSERT_EQ(simd_cloud.points.size(), static_cast<std::size_t>(count));
    ASSERT_EQ(simd_normals.normals.size(), static_cast<std::size_t>(count));
    EXPECT_EQ(simd_cloud.colors, cloud.colors);
    for (int k = 0; k < count; ++k) {
      ASSERT_EQ(std::memcmp(simd_cloud.points[k].data(), portable_cloud.points[k].data(),
                            sizeof(float) * 3), 0)
          << "trial " << trial << " point " << k << ": " << cloud.points[k].transpose() << " -> "
          << simd_cloud.points[k].transpose() << " / " << portable_cloud.points[k].transpose();
      ASSERT_EQ(std::memcmp(simd_normals.normals[k].data(), portable_normals.normals[k].data(),
                            sizeof(float) * 3), 0)
          << "trial " << trial << " normal " << k;
      compared += portable_cloud.points[k].allFinite();
    }
  }
  EXPECT_GT(compared, 2000u);  // else the comparison says little
}

}  // namespace
}  // namespace findmug
