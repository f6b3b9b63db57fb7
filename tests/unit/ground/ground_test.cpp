// Tests for ground.hpp: the plane from the camera mount, from floor labels
// (RANSAC), and estimated from the frame alone; synthetic scenes with known
// answers and real NYU Depth V2 frames.
#include "findmug/ground/ground.hpp"
#include "findmug/ground/ground_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "ground/ground_internal.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr float kDeg = static_cast<float>(M_PI / 180.0);

// The camera's "up" and "forward on the floor" in camera coordinates for a
// mount (pitch θ down, roll φ clockwise), derived by hand:
//   up      = (-sinφ cosθ, -cosφ cosθ, -sinθ)
//   forward = (-sinφ sinθ, -cosφ sinθ,  cosθ)
Eigen::Vector3f upInCamera(const CameraExtrinsics& m) {
  const double t = m.pitch_rad, f = m.roll_rad;
  return Eigen::Vector3d(-std::sin(f) * std::cos(t), -std::cos(f) * std::cos(t), -std::sin(t))
      .cast<float>();
}
Eigen::Vector3f forwardInCamera(const CameraExtrinsics& m) {
  const double t = m.pitch_rad, f = m.roll_rad;
  return Eigen::Vector3d(-std::sin(f) * std::sin(t), -std::cos(f) * std::sin(t), std::cos(t))
      .cast<float>();
}

float angleBetween(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0f, 1.0f));
}

// A ray-cast room: floor, optionally a table top (horizontal rectangle) and a
// wall across the view. Depth in mm with Gaussian noise, plus a label image.
struct Scene {
  CameraExtrinsics mount{1.3, 0.4, 0.05};
  bool floor = true;
  float table_height = 0.0f;  // 0 = no table
  float table_near = 0.0f, table_far = 0.0f, table_half_width = 0.0f;
  float wall_distance = 0.0f;  // 0 = no wall; forward distance from the camera
  // A ramp going down into the floor (a stairwell, a loading dock): from
  // forward distance ramp_near, sloping down by ramp_slope_rad, |lateral| < 0.8 m.
  float ramp_near = 0.0f, ramp_far = 0.0f, ramp_slope_rad = 0.0f;
  float noise_m = 0.0f;
  int width = 320, height = 240;
  CameraIntrinsics k{262.5, 262.5, 159.5, 119.5};
};

struct Rendered {
  RgbdFrame frame;
  OrganizedCloud cloud;
  std::vector<std::uint8_t> labels;
  int floor_pixels = 0, table_pixels = 0;
};

Rendered render(const Scene& s, std::uint64_t seed = 7) {
  const Eigen::Vector3f up = upInCamera(s.mount);
  const Eigen::Vector3f fwd = forwardInCamera(s.mount);
  const Eigen::Vector3f left = up.cross(fwd);
  const float h = static_cast<float>(s.mount.height_m);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, s.noise_m);

  RgbdFrame f;
  f.width = s.width;
  f.height = s.height;
  f.intrinsics = s.k;
  f.source = "synthetic scene";
  f.depth_mm.assign(static_cast<std::size_t>(s.width) * s.height, 0);
  f.rgb.assign(f.depth_mm.size(), Rgb8{128, 128, 128});
  Rendered out;
  out.labels.assign(f.depth_mm.size(), 0);
  for (int v = 0; v < s.height; ++v) {
    for (int u = 0; u < s.width; ++u) {
      const Eigen::Vector3f ray(static_cast<float>((u - s.k.cx) / s.k.fx),
                                static_cast<float>((v - s.k.cy) / s.k.fy), 1.0f);
      float best = 1e9f;
      std::uint8_t label = 0;
      const float up_r = up.dot(ray);
      auto inRamp = [&](const Eigen::Vector3f& p) {
        return s.ramp_far > 0.0f && fwd.dot(p) > s.ramp_near && fwd.dot(p) < s.ramp_far &&
               std::abs(left.dot(p)) < 0.8f;
      };
      if (s.floor && up_r < 0.0f) {
        const float t = -h / up_r;
        if (t < best && !inRamp(t * ray)) best = t, label = 1;
      }
      if (s.ramp_far > 0.0f) {
        // height = -(forward - near) * tan(slope)
        const float k = std::tan(s.ramp_slope_rad);
        const float t = -(h - s.ramp_near * k) / (up + k * fwd).dot(ray);
        if (t > 0.0f && t < best && inRamp(t * ray)) best = t, label = 0;
      }
      if (s.table_height > 0.0f && up_r != 0.0f) {
        const float t = (s.table_height - h) / up_r;
        const Eigen::Vector3f p = t * ray;
        if (t > 0.0f && t < best && fwd.dot(p) > s.table_near && fwd.dot(p) < s.table_far &&
            std::abs(left.dot(p)) < s.table_half_width) {
          best = t, label = 4;
        }
      }
      if (s.wall_distance > 0.0f && fwd.dot(ray) > 0.0f) {
        const float t = s.wall_distance / fwd.dot(ray);
        if (t < best) best = t, label = 2;
      }
      if (best > 9.5f) continue;
      const std::size_t i = static_cast<std::size_t>(v) * s.width + u;
      const float z = best + (s.noise_m > 0.0f ? noise(rng) : 0.0f);
      f.depth_mm[i] = static_cast<std::uint16_t>(std::lround(z * 1000.0f));
      out.labels[i] = label;
      out.floor_pixels += label == 1;
      out.table_pixels += label == 4;
    }
  }
  out.cloud = frameToCloud(f);
  out.frame = std::move(f);
  return out;
}

TEST(GroundFromExtrinsics, FloorPointMapsToZeroAndOneMetreAboveToOne) {
  const CameraExtrinsics m{1.2, 0.3, 0.1};
  const GroundPlane g = groundFromExtrinsics(m);
  const Eigen::Vector3f up = upInCamera(m);
  EXPECT_LT(angleBetween(g.normal_camera, up), 1e-4f) << g.normal_camera.transpose();
  EXPECT_NEAR(g.offset, 1.2f, 1e-5f);
  EXPECT_EQ(g.support_points, 0);

  // The optical axis meets the floor at depth h / sin(pitch), straight ahead.
  const Eigen::Vector3f on_floor(0, 0, static_cast<float>(1.2 / std::sin(0.3)));
  const Eigen::Vector3f q = g.camera_to_ground * on_floor;
  EXPECT_NEAR(q.z(), 0.0f, 1e-5f);
  EXPECT_NEAR(q.x(), static_cast<float>(1.2 / std::tan(0.3)), 1e-4f);  // forward
  EXPECT_NEAR(q.y(), 0.0f, 1e-5f);
  EXPECT_NEAR((g.camera_to_ground * Eigen::Vector3f(on_floor + up)).z(), 1.0f, 1e-5f);
  // The camera itself sits right above the origin.
  EXPECT_TRUE((g.camera_to_ground * Eigen::Vector3f::Zero()).isApprox(Eigen::Vector3f(0, 0, 1.2f)));
  // Image right (camera +x) rolled clockwise dips: it points partly down and
  // to the right (negative ground y).
  const Eigen::Vector3f right = g.camera_to_ground.linear() * Eigen::Vector3f::UnitX();
  EXPECT_LT(right.z(), -0.05f);
  EXPECT_LT(right.y(), -0.9f);
}

TEST(GroundFromExtrinsics, LevelCameraAndBadMount) {
  const GroundPlane g = groundFromExtrinsics({0.8, 0.0, 0.0});
  EXPECT_TRUE(g.normal_camera.isApprox(Eigen::Vector3f(0, -1, 0), 1e-6f));
  // 5 m ahead, 1 m to the right, 0.3 m above the camera.
  const Eigen::Vector3f p = g.camera_to_ground * Eigen::Vector3f(1.0f, -0.3f, 5.0f);
  EXPECT_TRUE(p.isApprox(Eigen::Vector3f(5.0f, -1.0f, 1.1f), 1e-5f)) << p.transpose();
  EXPECT_THROW(groundFromExtrinsics({-1.0, 0.0, 0.0}), Error);
  EXPECT_THROW(groundFromExtrinsics({1.0, std::nan(""), 0.0}), Error);
  EXPECT_THROW(groundFromExtrinsics({1.0, 0.0, 2.0}), Error);
}

TEST(GroundFromPlane, NormalisesOrientsAndBuildsRightHandedFrame) {
  // -2y - 3 = 0: the plane y = -1.5 (above the camera, as seen in camera
  // coordinates). The camera must end up on the positive side.
  const GroundPlane g = groundFromPlane(Eigen::Vector3f(0, -2, 0), -3.0f, 42);
  EXPECT_TRUE(g.normal_camera.isApprox(Eigen::Vector3f(0, 1, 0)));
  EXPECT_NEAR(g.offset, 1.5f, 1e-6f);
  EXPECT_EQ(g.support_points, 42);
  EXPECT_NEAR((g.camera_to_ground * Eigen::Vector3f(0.3f, -1.5f, 2.0f)).z(), 0.0f, 1e-6f);
  EXPECT_NEAR(g.camera_to_ground.linear().determinant(), 1.0f, 1e-5f);

  // Camera looking straight down: forward falls back to image "up" (-y).
  const GroundPlane down = groundFromPlane(Eigen::Vector3f(0, 0, -1), 1.0f, 0);
  EXPECT_NEAR(down.camera_to_ground.linear().determinant(), 1.0f, 1e-5f);
  EXPECT_TRUE((down.camera_to_ground.linear() * Eigen::Vector3f(0, -1, 0))
                  .isApprox(Eigen::Vector3f(1, 0, 0), 1e-5f));

  EXPECT_THROW(groundFromPlane(Eigen::Vector3f::Zero(), 1.0f, 0), Error);
  EXPECT_THROW(groundFromPlane(Eigen::Vector3f(0, -1, 0), std::nanf(""), 0), Error);
}

Scene roomWithTable() {
  Scene s;
  s.table_height = 0.75f;
  s.table_near = 1.2f;
  s.table_far = 2.2f;
  s.table_half_width = 0.5f;
  s.wall_distance = 4.0f;
  s.noise_m = 0.005f;
  return s;
}

TEST(FitGroundToLabels, RecoversFloorDespiteNoiseAndMislabels) {
  const Scene s = roomWithTable();
  Rendered r = render(s);
  ASSERT_GT(r.floor_pixels, 10000);
  // 20 % of the floor labels land on wrong depths (label bleeding, objects).
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> depth(0.5f, 5.0f);
  int outliers = 0;
  for (std::size_t i = 0; i < r.labels.size(); ++i) {
    if (r.labels[i] == 1 && rng() % 5 == 0) {
      r.cloud.points[i] *= depth(rng) / r.cloud.points[i].z();
      ++outliers;
    }
  }
  ASSERT_GT(outliers, 1000);
  GroundConfig config;
  const auto g = fitGroundToLabels(r.cloud, r.labels, config);
  ASSERT_TRUE(g.has_value());
  EXPECT_LT(angleBetween(g->normal_camera, upInCamera(s.mount)), 0.5f * kDeg);
  EXPECT_NEAR(g->offset, 1.3f, 0.01f);
  EXPECT_GT(g->support_points, (r.floor_pixels - outliers) * 9 / 10);
  EXPECT_LT(g->support_points, r.floor_pixels - outliers / 2);
  // Ground x runs along the viewing direction.
  const Eigen::Vector3f x_cam = g->camera_to_ground.linear().transpose() * Eigen::Vector3f::UnitX();
  EXPECT_LT(angleBetween(x_cam, forwardInCamera(s.mount)), 0.5f * kDeg);

  // Seeded: the same input gives the same plane.
  const auto again = fitGroundToLabels(r.cloud, r.labels, config);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->offset, g->offset);
  EXPECT_EQ(again->support_points, g->support_points);
}

TEST(FitGroundToLabels, TooFewFloorPointsOrBadInputs) {
  Rendered r = render(roomWithTable());
  int kept = 0;
  for (auto& l : r.labels)
    if (l == 1 && ++kept > 1500) l = 0;
  GroundConfig config;  // min_floor_points = 2000
  EXPECT_FALSE(fitGroundToLabels(r.cloud, r.labels, config).has_value());
  config.min_floor_points = 1000;
  EXPECT_TRUE(fitGroundToLabels(r.cloud, r.labels, config).has_value());

  // Floor labels on points that are no plane at all: no plane explains half.
  Rendered scattered = render(roomWithTable());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> depth(0.5f, 6.0f);
  for (std::size_t i = 0; i < scattered.labels.size(); ++i)
    if (scattered.labels[i] == 1)
      scattered.cloud.points[i] *= depth(rng) / scattered.cloud.points[i].z();
  EXPECT_FALSE(fitGroundToLabels(scattered.cloud, scattered.labels, GroundConfig{}).has_value());

  std::vector<std::uint8_t> short_labels(r.labels.begin(), r.labels.end() - 1);
  EXPECT_THROW(fitGroundToLabels(r.cloud, short_labels, config), Error);
  GroundConfig bad;
  bad.ransac_inlier_m = 0.0f;
  EXPECT_THROW(fitGroundToLabels(r.cloud, r.labels, bad), Error);
}

TEST(EstimateGround, PicksTheFloorNotTheBiggerTable) {
  Scene s = roomWithTable();
  s.mount = {1.4, 0.55, -0.04};
  s.table_near = 0.6f;
  s.table_far = 2.4f;
  s.table_half_width = 1.2f;
  s.wall_distance = 3.5f;
  const Rendered r = render(s);
  // The table must dominate, or "largest plane" would also pass.
  ASSERT_GT(r.table_pixels, 2 * r.floor_pixels) << r.floor_pixels;
  ASSERT_GT(r.floor_pixels, 5000) << r.table_pixels;
  const NormalImage normals = computeNormals(r.cloud, NormalConfig{});
  const auto g = estimateGround(r.cloud, normals, GroundConfig{});
  ASSERT_TRUE(g.has_value());
  EXPECT_LT(angleBetween(g->normal_camera, upInCamera(s.mount)), 1.0f * kDeg);
  EXPECT_NEAR(g->offset, 1.4f, 0.02f);
  EXPECT_GT(g->support_points, r.floor_pixels / 2);
  EXPECT_LE(g->support_points, r.floor_pixels);
}

TEST(ConfirmGround, KeepsTheFloorOfTheSameMountAndRejectsAnother) {
  const Scene s = roomWithTable();
  const Rendered first = render(s, 7);
  const auto g = estimateGround(first.cloud, computeNormals(first.cloud, NormalConfig{}),
                                GroundConfig{});
  ASSERT_TRUE(g.has_value());

  // The same mount, other sensor noise: the plane is kept as it was.
  const Rendered again = render(s, 8);
  const auto kept =
      confirmGround(again.cloud, computeNormals(again.cloud, NormalConfig{}), *g, GroundConfig{});
  ASSERT_TRUE(kept.has_value());
  EXPECT_EQ(kept->normal_camera, g->normal_camera);
  EXPECT_EQ(kept->offset, g->offset);
  EXPECT_NEAR(kept->support_points, g->support_points, 0.1 * g->support_points);

  // The camera 25 cm lower: the old floor lies above the new one.
  Scene lower = s;
  lower.mount.height_m -= 0.25;
  const Rendered moved = render(lower, 9);
  EXPECT_FALSE(
      confirmGround(moved.cloud, computeNormals(moved.cloud, NormalConfig{}), *g, GroundConfig{}));
  // Pitched 10 degrees further down: same height, tilted plane.
  Scene pitched = s;
  pitched.mount.pitch_rad += 10.0 * M_PI / 180.0;
  const Rendered tilted = render(pitched, 10);
  EXPECT_FALSE(confirmGround(tilted.cloud, computeNormals(tilted.cloud, NormalConfig{}), *g,
                             GroundConfig{}));

  // Most of the floor hidden (a wall 1.6 m ahead): less than 80 % support left.
  Scene blocked = s;
  blocked.wall_distance = 1.6f;
  blocked.table_height = 0.0f;
  const Rendered wall = render(blocked, 11);
  GroundConfig config;
  config.min_floor_points = 100;
  EXPECT_FALSE(confirmGround(wall.cloud, computeNormals(wall.cloud, NormalConfig{}), *g, config));
  config.reuse_min_support_fraction = 0.01f;
  EXPECT_TRUE(confirmGround(wall.cloud, computeNormals(wall.cloud, NormalConfig{}), *g, config));
}

TEST(SegmenterGround, ReestimatesEveryNFramesAndWhenTheCheckFails) {
  const Scene s = roomWithTable();
  Scene lower = s;
  lower.mount.height_m -= 0.25;
  const Rendered a1 = render(s, 1), a2 = render(s, 2), a3 = render(s, 3), b = render(lower, 4);
  auto estimated = [](const Rendered& r) {
    return *estimateGround(r.cloud, computeNormals(r.cloud, NormalConfig{}), GroundConfig{});
  };
  auto planeOf = [](const Segmenter& seg, GroundTracker& stream, const Rendered& r) {
    const PreparedFrame p = seg.prepare(r.frame, stream);
    EXPECT_TRUE(p.ground.has_value());
    return p.ground.value_or(GroundPlane{});
  };
  // Noise makes every frame's own estimate differ a little.
  ASSERT_NE(estimated(a1).offset, estimated(a2).offset);

  SegmenterConfig config;
  config.ground.source = GroundSource::Estimated;
  {
    // Default: every frame its own estimate.
    const Segmenter seg(config, nullptr);
    GroundTracker stream;
    EXPECT_EQ(planeOf(seg, stream, a1).offset, estimated(a1).offset);
    EXPECT_EQ(planeOf(seg, stream, a2).offset, estimated(a2).offset);
    EXPECT_FALSE(stream.plane().has_value());  // nothing kept
  }
  config.ground.reestimate_every_frames = 2;
  {
    const Segmenter seg(config, nullptr);
    GroundTracker stream;
    EXPECT_EQ(planeOf(seg, stream, a1).offset, estimated(a1).offset);
    EXPECT_EQ(planeOf(seg, stream, a2).offset, estimated(a1).offset);  // kept
    EXPECT_EQ(stream.framesSinceEstimate(), 1);
    EXPECT_EQ(planeOf(seg, stream, a3).offset, estimated(a3).offset);  // second frame: estimated again
    EXPECT_EQ(stream.framesSinceEstimate(), 0);
  }
  config.ground.reestimate_every_frames = 100;
  {
    const Segmenter seg(config, nullptr);
    GroundTracker stream;
    EXPECT_EQ(planeOf(seg, stream, a1).offset, estimated(a1).offset);
    EXPECT_EQ(planeOf(seg, stream, a2).offset, estimated(a1).offset);
    EXPECT_EQ(planeOf(seg, stream, a3).offset, estimated(a1).offset);
    // Another mount: the check fails and the floor is estimated again.
    EXPECT_EQ(planeOf(seg, stream, b).offset, estimated(b).offset);
    EXPECT_NEAR(planeOf(seg, stream, b).offset, lower.mount.height_m, 0.03);
    // Frames prepared without a tracker are each their own estimate, whatever the setting.
    EXPECT_EQ(seg.prepare(a2.frame).ground.value_or(GroundPlane{}).offset, estimated(a2).offset);
  }
}

TEST(SegmenterGround, TheStreamKeepsItsFloorAcrossSegmenters) {
  // A model reload builds a new Segmenter; the stream's tracker, not the Segmenter, holds
  // the floor, so the frames after the reload keep the plane found before it.
  const Scene s = roomWithTable();
  const Rendered a1 = render(s, 1), a2 = render(s, 2);
  const auto own = *estimateGround(a2.cloud, computeNormals(a2.cloud, NormalConfig{}),
                                   GroundConfig{});
  SegmenterConfig config;
  config.ground.source = GroundSource::Estimated;
  config.ground.reestimate_every_frames = 30;
  GroundTracker stream;
  const PreparedFrame before = Segmenter(config, nullptr).prepare(a1.frame, stream);
  ASSERT_TRUE(before.ground.has_value());
  const PreparedFrame after = Segmenter(config, nullptr).prepare(a2.frame, stream);
  ASSERT_TRUE(after.ground.has_value());
  EXPECT_EQ(after.ground->offset, before.ground->offset);
  EXPECT_NE(after.ground->offset, own.offset);
  EXPECT_EQ(stream.framesSinceEstimate(), 1);
}

TEST(EstimateGround, SlopedSurfaceBelowFloorLevelIsNotTheFloor) {
  // A ramp sinking 20 degrees into the floor: its points are the lowest
  // near-horizontal surface in view, but its normal disagrees with the
  // (larger) floor's, so the floor must win.
  Scene s;
  s.mount = {1.3, 0.45, 0.0};
  s.ramp_near = 1.5f;
  s.ramp_far = 4.5f;
  s.ramp_slope_rad = 20.0f * kDeg;
  s.noise_m = 0.003f;
  const Rendered r = render(s);
  int ramp_pixels = 0;
  for (std::size_t i = 0; i < r.labels.size(); ++i)
    ramp_pixels += r.labels[i] == 0 && r.cloud.valid(i);
  ASSERT_GT(ramp_pixels, 3 * GroundConfig{}.min_floor_points);
  const NormalImage normals = computeNormals(r.cloud, NormalConfig{});
  const auto g = estimateGround(r.cloud, normals, GroundConfig{});
  ASSERT_TRUE(g.has_value());
  EXPECT_LT(angleBetween(g->normal_camera, upInCamera(s.mount)), 1.0f * kDeg);
  EXPECT_NEAR(g->offset, 1.3f, 0.02f);
}

TEST(EstimateGround, NoVisibleFloorGivesNothing) {
  // Looking slightly up at a wall 2 m away: nothing horizontal in view.
  Scene s;
  s.mount = {1.5, -0.3, 0.0};
  s.wall_distance = 2.0f;
  s.noise_m = 0.003f;
  Rendered r = render(s);
  ASSERT_EQ(r.floor_pixels, 0);
  NormalImage normals = computeNormals(r.cloud, NormalConfig{});
  EXPECT_FALSE(estimateGround(r.cloud, normals, GroundConfig{}).has_value());

  // Only a thin strip of floor at the wall's foot: too little support.
  s.mount = {1.5, 0.23, 0.0};
  r = render(s);
  ASSERT_GT(r.floor_pixels, 0);
  ASSERT_LT(r.floor_pixels, GroundConfig{}.min_floor_points);
  normals = computeNormals(r.cloud, NormalConfig{});
  EXPECT_FALSE(estimateGround(r.cloud, normals, GroundConfig{}).has_value());

  NormalImage wrong = normals;
  wrong.normals.pop_back();
  EXPECT_THROW(estimateGround(r.cloud, wrong, GroundConfig{}), Error);
}

TEST(EstimateGround, TableWithoutFloorIsNotTakenForTheFloor) {
  Scene s = roomWithTable();
  s.floor = false;  // e.g. the floor is out of view or invalid depth
  s.table_half_width = 3.0f;
  const Rendered r = render(s);
  ASSERT_GT(r.table_pixels, 10000);
  const NormalImage normals = computeNormals(r.cloud, NormalConfig{});
  GroundConfig config;  // min_camera_height_m = 0.8; the table is 0.55 m below
  EXPECT_FALSE(estimateGround(r.cloud, normals, config).has_value());
  // Without the height prior the lowest horizontal plane is the table.
  config.min_camera_height_m = 0.3f;
  const auto g = estimateGround(r.cloud, normals, config);
  ASSERT_TRUE(g.has_value());
  EXPECT_NEAR(g->offset, 1.3f - 0.75f, 0.02f);
}

// ---------------------------------------------------------------------------
// groundFromGravity

TEST(GroundFromGravity, LabelledFloorGivesTheHeight) {
  const Scene s = roomWithTable();
  const Rendered r = render(s);
  const NormalImage normals = computeNormals(r.cloud, NormalConfig{});
  const Eigen::Vector3f up = upInCamera(s.mount);
  const auto g = groundFromGravity(r.cloud, normals, up, &r.labels, GroundConfig{});
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->method, GroundMethod::GravityFloorLabels);
  EXPECT_STREQ(groundMethodName(g->method), "gravity+floor_labels");
  EXPECT_LT(angleBetween(g->normal_camera, up), 1e-4f);
  EXPECT_NEAR(g->offset, 1.3f, 0.01f);
  EXPECT_EQ(g->support_points, r.floor_pixels);
  // The floor maps to z = 0, the table top to its height.
  for (std::size_t i = 0; i < r.labels.size(); i += 97) {
    if (!r.cloud.valid(i)) continue;
    const float z = (g->camera_to_ground * r.cloud.points[i]).z();
    if (r.labels[i] == 1) {
      EXPECT_NEAR(z, 0.0f, 0.03f);
    } else if (r.labels[i] == 4) {
      EXPECT_NEAR(z, 0.75f, 0.03f);
    }
  }
}

TEST(GroundFromGravity, SlightlyWrongGravityIsRefinedByTheFloorPlane) {
  const Scene s = roomWithTable();
  const Rendered r = render(s);
  const NormalImage normals = computeNormals(r.cloud, NormalConfig{});
  const Eigen::Vector3f truth = upInCamera(s.mount);
  // Gravity 5 degrees off (about the optical axis, as NYU's rotations are).
  const Eigen::Vector3f off5 = Eigen::AngleAxisf(5.0f * kDeg, Eigen::Vector3f::UnitZ()) * truth;
  const Eigen::Vector3f off15 = Eigen::AngleAxisf(15.0f * kDeg, Eigen::Vector3f::UnitZ()) * truth;
  for (const auto* labels : {&r.labels, static_cast<const std::vector<std::uint8_t>*>(nullptr)}) {
    const auto g = groundFromGravity(r.cloud, normals, off5, labels, GroundConfig{});
    ASSERT_TRUE(g.has_value());
    EXPECT_EQ(g->method,
              labels ? GroundMethod::GravityFloorLabels : GroundMethod::GravityLowestPlane);
    EXPECT_LT(angleBetween(g->normal_camera, truth), 0.5f * kDeg);
    EXPECT_NEAR(g->offset, 1.3f, 0.02f);
    // Beyond gravity_refine_deg the given direction is kept.
    const auto h = groundFromGravity(r.cloud, normals, off15, labels, GroundConfig{});
    ASSERT_TRUE(h.has_value());
    EXPECT_LT(angleBetween(h->normal_camera, off15), 1e-3f);
    // With refinement off, the given direction is kept too.
    GroundConfig keep;
    keep.gravity_refine_deg = 0.0f;
    const auto k = groundFromGravity(r.cloud, normals, off5, labels, keep);
    ASSERT_TRUE(k.has_value());
    EXPECT_LT(angleBetween(k->normal_camera, off5), 1e-3f);
  }
}

TEST(GroundFromGravity, WithoutLabelsTheLowestSurfaceNotTheBiggerTable) {
  Scene s = roomWithTable();
  s.mount = {1.4, 0.55, -0.04};
  s.table_near = 0.6f;
  s.table_far = 2.4f;
  s.table_half_width = 1.2f;
  s.wall_distance = 3.5f;
  const Rendered r = render(s);
  ASSERT_GT(r.table_pixels, 2 * r.floor_pixels);
  const NormalImage normals = computeNormals(r.cloud, NormalConfig{});
  const auto g = groundFromGravity(r.cloud, normals, upInCamera(s.mount), nullptr, GroundConfig{});
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->method, GroundMethod::GravityLowestPlane);
  EXPECT_NEAR(g->offset, 1.4f, 0.02f);

  // Too few labelled floor pixels: the labels are not trusted, the frame is.
  std::vector<std::uint8_t> few(r.labels.size(), 0);
  for (std::size_t i = 0, n = 0; i < r.labels.size() && n < 100; ++i)
    if (r.labels[i] == 1) few[i] = 1, ++n;
  const auto h = groundFromGravity(r.cloud, normals, upInCamera(s.mount), &few, GroundConfig{});
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->method, GroundMethod::GravityLowestPlane);
  EXPECT_NEAR(h->offset, 1.4f, 0.02f);
}

// Hand-made cloud from a level camera (up = -y): a table top 0.55 m below
// the camera and, optionally, a vertical front (a cabinet) 3 m ahead
// reaching from the camera's height down to `front_bottom` below it.
struct HandMade {
  OrganizedCloud cloud;
  NormalImage normals;
};
HandMade tableAndFront(float front_bottom, int front_rows) {
  HandMade out;
  const int w = 100, table_rows = 100;
  out.cloud.width = out.normals.width = w;
  out.cloud.height = out.normals.height = table_rows + front_rows;
  for (int v = 0; v < table_rows; ++v) {
    for (int u = 0; u < w; ++u) {
      out.cloud.points.emplace_back(-0.5f + 0.01f * u, 0.55f, 0.8f + 0.01f * v);
      out.normals.normals.emplace_back(0.0f, -1.0f, 0.0f);
    }
  }
  for (int v = 0; v < front_rows; ++v) {
    for (int u = 0; u < w; ++u) {
      const float below = front_bottom * (v + 0.5f) / front_rows;
      out.cloud.points.emplace_back(-0.5f + 0.01f * u, below, 3.0f);
      out.normals.normals.emplace_back(0.0f, 0.0f, -1.0f);
    }
  }
  out.cloud.colors.assign(out.cloud.points.size(), Rgb8{0, 0, 0});
  return out;
}

TEST(GroundFromGravity, OnlyATableInViewGivesTheHeightPrior) {
  // The table 0.55 m below the camera is less than min_camera_height_m
  // (0.8 m) below it: not the floor, which is out of view.
  const HandMade m = tableAndFront(0.0f, 0);
  GroundConfig config;
  const auto g = groundFromGravity(m.cloud, m.normals, Eigen::Vector3f(0, -1, 0), nullptr, config);
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->method, GroundMethod::GravityHeightPrior);
  EXPECT_STREQ(groundMethodName(g->method), "gravity+height_prior");
  EXPECT_NEAR(g->offset, config.prior_camera_height_m, 1e-5f);
  // The same surface with min_camera_height_m lowered is taken as the floor.
  config.min_camera_height_m = 0.5f;
  const auto h = groundFromGravity(m.cloud, m.normals, Eigen::Vector3f(0, -1, 0), nullptr, config);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->method, GroundMethod::GravityLowestPlane);
  EXPECT_NEAR(h->offset, 0.55f, 1e-3f);
  EXPECT_EQ(h->support_points, 10000);
}

TEST(GroundFromGravity, FurnitureReachingBelowTheTableGivesTheFloor) {
  // 5000 front points spread evenly over 0..1.5 m below the camera: the
  // 1 % height of all 15000 points is the 150th lowest, i.e. front row 150/100
  // from the bottom: 1.5 * (1 - 1.5/50) ~ 1.455 m below. That is far below
  // the table (0.55 m), so the table is not the floor, and below the prior
  // camera height (1.29 m), so it is not the prior either.
  const HandMade m = tableAndFront(1.5f, 50);
  GroundConfig config;
  const auto g = groundFromGravity(m.cloud, m.normals, Eigen::Vector3f(0, -1, 0), nullptr, config);
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->method, GroundMethod::GravityLowPercentile);
  EXPECT_NEAR(g->offset, 1.5f * (1.0f - 1.5f / 50.0f), 0.015f);
  EXPECT_STREQ(groundMethodName(g->method), "gravity+low_percentile");

  // A front that ends just below the table top (within the margin) is the
  // table's own edge: the table stays the lowest plane (allowed as the floor
  // here by lowering min_camera_height_m).
  const HandMade edge = tableAndFront(0.6f, 50);
  GroundConfig low_camera = config;
  low_camera.min_camera_height_m = 0.5f;
  const auto e =
      groundFromGravity(edge.cloud, edge.normals, Eigen::Vector3f(0, -1, 0), nullptr, low_camera);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->method, GroundMethod::GravityLowestPlane);
  EXPECT_NEAR(e->offset, 0.55f, 1e-3f);

  // No horizontal surface at all (only the front): the percentile.
  HandMade front = tableAndFront(1.5f, 50);
  for (auto& n : front.normals.normals) n = Eigen::Vector3f(0, 0, -1);
  const auto f =
      groundFromGravity(front.cloud, front.normals, Eigen::Vector3f(0, -1, 0), nullptr, config);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->method, GroundMethod::GravityLowPercentile);
}

TEST(GroundFromGravity, BadInputsAndNothingBelowTheCamera) {
  const HandMade m = tableAndFront(0.0f, 0);
  GroundConfig config;
  EXPECT_THROW(groundFromGravity(m.cloud, m.normals, Eigen::Vector3f::Zero(), nullptr, config),
               Error);
  std::vector<std::uint8_t> short_labels(10, 1);
  EXPECT_THROW(
      groundFromGravity(m.cloud, m.normals, Eigen::Vector3f(0, -1, 0), &short_labels, config),
      Error);
  NormalImage wrong = m.normals;
  wrong.normals.pop_back();
  EXPECT_THROW(groundFromGravity(m.cloud, wrong, Eigen::Vector3f(0, -1, 0), nullptr, config),
               Error);
  config.floor_percentile = 80.0f;
  EXPECT_THROW(groundFromGravity(m.cloud, m.normals, Eigen::Vector3f(0, -1, 0), nullptr, config),
               Error);
  // No valid point at all: no ground.
  HandMade empty = m;
  for (auto& p : empty.cloud.points) p = Eigen::Vector3f::Constant(std::nanf(""));
  EXPECT_FALSE(groundFromGravity(empty.cloud, empty.normals, Eigen::Vector3f(0, -1, 0), nullptr,
                                 GroundConfig{})
                   .has_value());
}

// NYU's per-frame rotations (camera_rotations_NYU.txt): on every labelled
// frame whose floor labels give a plane (the paper's protocol), the gravity
// "up" read with nyuUpFromRotation must agree with that plane's normal.
// Measured (perf-log §1d): see the printed angles.
TEST(GroundOnNyu, GravityFromRotationsAgreesWithFloorLabelFit) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations_file, "nyuv2_meta/camera_rotations_NYU.txt");
  DatasetOptions options;
  options.nyu_rotations_file = rotations_file.string();
  const DatasetFolder folder(root.string(), options);
  ASSERT_EQ(folder.size(), 31u);
  const NyuRotations rotations = loadNyuRotations(rotations_file.string());
  int compared = 0;
  float worst = 0.0f, worst_transposed = 0.0f, sum = 0.0f;
  for (std::size_t i = 0; i < folder.size(); ++i) {
    const LabeledFrame f = folder.load(i);
    ASSERT_TRUE(f.frame.gravity_up.has_value()) << f.name;
    const auto& g = *f.frame.gravity_up;
    const Eigen::Vector3f up(static_cast<float>(g[0]), static_cast<float>(g[1]),
                             static_cast<float>(g[2]));
    const OrganizedCloud cloud = frameToCloud(f.frame);
    const auto fit = fitGroundToLabels(cloud, f.labels, GroundConfig{});
    if (!fit) continue;
    const float angle = angleBetween(fit->normal_camera, up) / kDeg;
    std::printf("%s: gravity vs floor-label fit %.2f deg\n", f.name.c_str(), angle);
    EXPECT_LT(angle, 7.5f) << f.name;
    worst = std::max(worst, angle);
    sum += angle;
    // The transposed reading (a column of R instead of a row) is a different
    // direction; on some frames far off, so the test tells them apart.
    const auto& r = rotations.rotations[static_cast<std::size_t>(std::stol(f.name) - 1)];
    const Eigen::Vector3f column(static_cast<float>(-r[1]), static_cast<float>(-r[4]),
                                 static_cast<float>(-r[7]));
    worst_transposed = std::max(worst_transposed, angleBetween(fit->normal_camera, column) / kDeg);
    ++compared;
  }
  RecordProperty("worst_angle_deg", std::to_string(worst));
  EXPECT_GE(compared, 12);
  EXPECT_LT(sum / compared, 4.0f);
  EXPECT_GT(worst_transposed, 10.0f);
}

// With ground.source=gravity every one of the 31 frames gets a ground frame
// (the paper's floor_labels protocol keeps 14), and the way it was obtained
// is the labelled floor wherever there is enough of it.
TEST(GroundOnNyu, GravitySourceGivesEveryFrameAGround) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations_file, "nyuv2_meta/camera_rotations_NYU.txt");
  DatasetOptions options;
  options.nyu_rotations_file = rotations_file.string();
  const DatasetFolder folder(root.string(), options);
  ASSERT_EQ(folder.size(), 31u);
  SegmenterConfig config;
  config.ground.source = GroundSource::Gravity;
  const Segmenter segmenter(config, nullptr);
  int with_labels = 0;
  for (std::size_t i = 0; i < folder.size(); ++i) {
    LabeledFrame f = folder.load(i);
    int floor = 0;
    for (auto l : f.labels) floor += l == 1;
    const PreparedFrame p = segmenter.prepare(std::move(f.frame), &f.labels);
    ASSERT_TRUE(p.ground.has_value()) << f.name;
    std::printf("%s: %s, camera %.2f m above the floor\n", f.name.c_str(),
                groundMethodName(p.ground->method), p.ground->offset);
    // A hand-held Kinect: 0.8..2.2 m above whatever was taken as the floor.
    EXPECT_GT(p.ground->offset, 0.8f) << f.name;
    EXPECT_LT(p.ground->offset, 2.2f) << f.name;
    if (floor >= GroundConfig{}.min_floor_points) {
      EXPECT_EQ(p.ground->method, GroundMethod::GravityFloorLabels) << f.name;
      ++with_labels;
    } else {
      EXPECT_NE(p.ground->method, GroundMethod::GravityFloorLabels) << f.name;
    }
  }
  EXPECT_GE(with_labels, 12);
}

// The label-free part of groundFromGravity, checked where the answer is known:
// on the frames with a labelled floor, withholding the labels, the floor
// height found from the frame alone must agree with the labelled floor's.
TEST(GroundOnNyu, GravityWithoutLabelsFindsTheLabelledFloorHeight) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations_file, "nyuv2_meta/camera_rotations_NYU.txt");
  DatasetOptions options;
  options.nyu_rotations_file = rotations_file.string();
  const DatasetFolder folder(root.string(), options);
  const GroundConfig config;
  int compared = 0, from_plane = 0;
  for (std::size_t i = 0; i < folder.size(); ++i) {
    const LabeledFrame f = folder.load(i);
    const auto& g = *f.frame.gravity_up;
    const Eigen::Vector3f up(static_cast<float>(g[0]), static_cast<float>(g[1]),
                             static_cast<float>(g[2]));
    const OrganizedCloud cloud = frameToCloud(f.frame);
    const NormalImage normals = computeNormals(cloud, NormalConfig{});
    // Where the labelled floor gives a plane (the paper's protocol), so the
    // reference is a fitted plane, not a median height of few floor points.
    if (!fitGroundToLabels(cloud, f.labels, config)) continue;
    const auto with = groundFromGravity(cloud, normals, up, &f.labels, config);
    ASSERT_TRUE(with.has_value()) << f.name;
    ASSERT_EQ(with->method, GroundMethod::GravityFloorLabels) << f.name;
    const auto without = groundFromGravity(cloud, normals, up, nullptr, config);
    ASSERT_TRUE(without.has_value()) << f.name;
    std::printf("%s: labelled floor %.3f m below the camera, without labels %.3f m (%s)\n",
                f.name.c_str(), with->offset, without->offset, groundMethodName(without->method));
    if (without->method == GroundMethod::GravityLowestPlane) {
      EXPECT_NEAR(without->offset, with->offset, 0.06f) << f.name;
      EXPECT_LT(angleBetween(without->normal_camera, with->normal_camera), 2.0f * kDeg) << f.name;
      ++from_plane;
    } else {
      EXPECT_NEAR(without->offset, with->offset, 0.3f) << f.name;
    }
    ++compared;
  }
  EXPECT_GE(compared, 12);
  EXPECT_GE(from_plane * 4, compared * 3);  // the visible floor is found as a plane
}

// NYU Depth V2 labeled frames: wherever the floor-label fit (the paper's
// protocol) accepts a frame, the label-free estimate must find the same floor
// or (only when the floor is small) nothing.
// Frames with no floor in view must mostly come back empty, not with a table.
TEST(GroundOnNyu, EstimateAgreesWithFloorLabelFit) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  int compared = 0, no_floor = 0, no_floor_rejected = 0;
  for (const auto& entry : std::filesystem::directory_iterator(root / "label8")) {
    const std::string name = entry.path().stem().string();
    const auto labels = readPng8(entry.path().string());
    const auto depth = readPng16((root / "depth" / (name + ".png")).string());
    const auto rgb = readPngRgb((root / "rgb" / (name + ".png")).string());
    RgbdFrame f;
    f.width = depth.width;
    f.height = depth.height;
    f.depth_mm = depth.pixels;
    f.rgb = rgb.pixels;
    f.intrinsics = kNyuIntrinsics;
    f.source = name;
    // NYU's projection mask: depth outside it is inpainting, not measurement.
    for (int v = 0; v < f.height; ++v)
      for (int u = 0; u < f.width; ++u)
        if (v < 44 || v >= 471 || u < 40 || u >= 601) f.depth_mm[v * f.width + u] = 0;
    const OrganizedCloud cloud = frameToCloud(f);
    int floor = 0;
    for (std::size_t i = 0; i < labels.pixels.size(); ++i)
      floor += labels.pixels[i] == 1 && cloud.valid(i);

    GroundConfig config;
    const auto fit = fitGroundToLabels(cloud, labels.pixels, config);
    const auto est = estimateGround(cloud, computeNormals(cloud, NormalConfig{}), config);
    if (floor == 0) {
      ++no_floor;
      no_floor_rejected += !est.has_value();
    }
    if (!fit) continue;
    // With plenty of floor the estimate must find it; with little (a few
    // thousand pixels) it may give up, but never return a different plane.
    if (floor >= 5000) {
      ASSERT_TRUE(est.has_value()) << name;
    } else if (!est) {
      continue;
    }
    const float angle = angleBetween(fit->normal_camera, est->normal_camera);
    EXPECT_LT(angle, 2.0f * kDeg) << name;
    EXPECT_NEAR(fit->offset, est->offset, 0.05f) << name;
    // A hand-held Kinect in a room: the camera is 0.8..2 m above the floor.
    EXPECT_GT(fit->offset, 0.8f) << name;
    EXPECT_LT(fit->offset, 2.0f) << name;
    ++compared;
  }
  EXPECT_GE(compared, 10);
  ASSERT_GE(no_floor, 5);
  EXPECT_GE(no_floor_rejected * 4, no_floor * 3) << no_floor_rejected << " of " << no_floor;
}


// The AVX2 support tests of estimateGround against the portable ones, on
// points placed within a rounding error of the distance and angle limits,
// where any change in the order of the arithmetic flips some of them.
TEST(GroundSimd, SupportTestsMatchThePortableCodeBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> sizes(0, 700);
  const float tol = 0.02f, cos_agree = std::cos(15.0f * kDeg);
  std::size_t inside = 0, total = 0, count_total = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Vector3f n =
        Eigen::Vector3f(0.3f * unit(rng), -1.0f, 0.3f * unit(rng)).normalized();
    const float offset = 1.0f + unit(rng);
    const Eigen::Vector3f t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    const int size = sizes(rng);
    std::vector<Eigen::Vector3f> points(size), normals(size);
    for (int k = 0; k < size; ++k) {
      // On the plane, then out along the normal by about the tolerance.
      const Eigen::Vector3f on = -offset * n + 3.0f * unit(rng) * t1 + 3.0f * unit(rng) * t2;
      const float out = tol * (1.0f + 2e-6f * unit(rng)) * (unit(rng) < 0.0f ? -1.0f : 1.0f);
      points[k] = on + out * n;
      // A normal about the agreement angle away from the plane's.
      const float angle = std::acos(cos_agree) * (1.0f + 1e-5f * unit(rng));
      const Eigen::Vector3f side = (unit(rng) * t1 + unit(rng) * t2).normalized();
      normals[k] = std::cos(angle) * n + std::sin(angle) * side;
      if (k % 97 == 5) points[k].z() = std::numeric_limits<float>::quiet_NaN();
      if (k % 89 == 7) normals[k].x() = std::numeric_limits<float>::infinity();
    }
    const auto simd = detail::planeSupport(points, normals, n, offset, tol, cos_agree,
                                           detail::GroundSimd::Auto);
    const auto portable = detail::planeSupport(points, normals, n, offset, tol, cos_agree,
                                               detail::GroundSimd::Off);
    ASSERT_EQ(simd, portable) << "trial " << trial << ", " << size << " points";
    const std::size_t count = detail::planeSupportCount(points, normals, n, offset, tol,
                                                        cos_agree, detail::GroundSimd::Auto);
    ASSERT_EQ(count, detail::planeSupportCount(points, normals, n, offset, tol, cos_agree,
                                               detail::GroundSimd::Off))
        << "trial " << trial;
    inside += portable.size();
    count_total += count;
    total += static_cast<std::size_t>(size);
  }
  // Both sides of the limits are represented, so a changed rounding shows.
  EXPECT_GT(inside, total / 10);
  EXPECT_LT(inside, total * 9 / 10);
  EXPECT_GT(count_total, total / 10);
  EXPECT_LT(count_total, total * 9 / 10);
}

// The whole estimate with and without the AVX2 paths: the same plane to the
// bit, on every NYU frame and on rendered rooms.
TEST(GroundSimd, EstimateMatchesThePortableCodeBitForBit) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  std::vector<OrganizedCloud> clouds;
  const DatasetFolder dataset(root.string());
  for (std::size_t index = 0; index < dataset.size(); ++index) {
    clouds.push_back(frameToCloud(dataset.load(index).frame));
  }
  ASSERT_GE(clouds.size(), 30u);
  for (int seed = 1; seed <= 6; ++seed) {
    Scene s;
    s.table_height = seed % 2 ? 0.75f : 0.0f;
    s.table_near = 1.0f, s.table_far = 2.0f, s.table_half_width = 0.6f;
    s.wall_distance = seed % 3 ? 4.0f : 0.0f;
    s.noise_m = 0.004f * static_cast<float>(seed);
    clouds.push_back(render(s, static_cast<std::uint64_t>(seed)).cloud);
  }
  int planes = 0;
  for (std::size_t c = 0; c < clouds.size(); ++c) {
    const NormalImage normals = computeNormals(clouds[c], NormalConfig{});
    const GroundConfig config;
    const auto simd = detail::estimateGround(clouds[c], normals, config, detail::GroundSimd::Auto);
    const auto portable =
        detail::estimateGround(clouds[c], normals, config, detail::GroundSimd::Off);
    ASSERT_EQ(simd.has_value(), portable.has_value()) << "cloud " << c;
    if (!simd) continue;
    ++planes;
    EXPECT_EQ(0, std::memcmp(simd->normal_camera.data(), portable->normal_camera.data(),
                             sizeof(float) * 3))
        << "cloud " << c;
    EXPECT_EQ(0, std::memcmp(&simd->offset, &portable->offset, sizeof(float))) << "cloud " << c;
    EXPECT_EQ(simd->support_points, portable->support_points) << "cloud " << c;
  }
  EXPECT_GE(planes, 15);
}

}  // namespace
}  // namespace findmug
