// findmug/ground.hpp — the ground plane and the ground-aligned frame.
//
// All height and angle features, and all table geometry, live in a
// ground-aligned frame: z up (floor normal), floor at z = 0, x along the
// camera's viewing direction projected on the floor, origin below the
// camera. For a robot with the camera above its base this is the base frame.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "findmug/cloud.hpp"
#include "findmug/frame.hpp"

namespace findmug {

struct GroundPlane {
  // Plane in the camera frame: normal.dot(p) + offset = 0, normal unit and
  // pointing up (away from the floor, towards the camera side).
  Eigen::Vector3f normal_camera = Eigen::Vector3f(0, -1, 0);
  float offset = 0.0f;
  // Maps camera-frame points into the ground-aligned frame.
  Eigen::Isometry3f camera_to_ground = Eigen::Isometry3f::Identity();
  int support_points = 0;  // inliers that produced it (0 when from extrinsics)
};

enum class GroundSource {
  Extrinsics,    // from the camera mount (robot)
  FloorLabels,   // RANSAC on ground-truth floor pixels (the paper's protocol)
  Estimated,     // dominant horizontal plane found in the frame alone
};

struct GroundConfig {
  GroundSource source = GroundSource::Extrinsics;
  float ransac_inlier_m = 0.03f;
  int ransac_iterations = 200;
  int min_floor_points = 2000;     // fewer floor points: the frame is dropped
  float max_tilt_deg = 45.0f;      // estimated floor normal vs camera "up" (-y)
  std::uint64_t seed = 1;
};

// Builds the plane and transform from a known camera mount.
GroundPlane groundFromExtrinsics(const CameraExtrinsics& extrinsics);

// Builds the ground frame from a plane (normal, offset) in the camera frame.
GroundPlane groundFromPlane(const Eigen::Vector3f& normal_camera, float offset, int support);

// RANSAC on the points whose label (same grid as the cloud) is Floor.
// Returns nullopt when fewer than `min_floor_points` floor points exist or
// no plane with enough inliers is found.
std::optional<GroundPlane> fitGroundToLabels(const OrganizedCloud& cloud_camera,
                                             const std::vector<std::uint8_t>& labels,
                                             const GroundConfig& config);

// Finds the dominant roughly-horizontal plane low in the scene, using the
// normals; for frames whose camera mount is unknown.
std::optional<GroundPlane> estimateGround(const OrganizedCloud& cloud_camera,
                                          const NormalImage& normals_camera,
                                          const GroundConfig& config);

}  // namespace findmug
