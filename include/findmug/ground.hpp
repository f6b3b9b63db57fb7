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
  Auto,          // extrinsics when the frame carries them, else Estimated
  Extrinsics,    // from the camera mount (robot); a frame without them is an error
  FloorLabels,   // RANSAC on ground-truth floor pixels (the paper's protocol)
  Estimated,     // dominant horizontal plane found in the frame alone
};

struct GroundConfig {
  GroundSource source = GroundSource::Auto;
  float ransac_inlier_m = 0.03f;
  int ransac_iterations = 200;
  int min_floor_points = 2000;     // fewer floor points: the frame is dropped
  float max_tilt_deg = 45.0f;      // estimated floor normal vs camera "up" (-y)
  std::uint64_t seed = 1;
  // fitGroundToLabels: the plane must explain at least this share of the
  // floor-labelled points (label noise at object feet and mislabels are the rest).
  float min_inlier_fraction = 0.5f;
  // estimateGround: a point supports a plane only if its normal is within
  // this angle of the plane normal (keeps chair legs, box sides out).
  float normal_agreement_deg = 20.0f;
  // estimateGround: the lowest horizontal plane must lie at least this far
  // below the camera, or the frame is taken to show no floor. When no floor
  // is visible the lowest plane is a table or seat, typically 0.4..0.7 m
  // below a hand-held camera; a real floor is >= 1 m below on NYU. A camera
  // mounted lower than this must use GroundSource::Extrinsics (or lower it).
  float min_camera_height_m = 0.8f;
};

// Builds the plane and transform from a known camera mount.
GroundPlane groundFromExtrinsics(const CameraExtrinsics& extrinsics);

// Builds the ground frame from a plane (normal, offset) in the camera frame.
// The normal need not be unit; the sign is flipped if needed so that the
// camera is on the positive side (above the floor). Throws on a zero or
// non-finite normal or offset.
GroundPlane groundFromPlane(const Eigen::Vector3f& normal_camera, float offset, int support);

// RANSAC on the points whose label (same grid as the cloud) is Floor.
// Returns nullopt when fewer than `min_floor_points` floor points exist or
// no plane with enough inliers is found.
std::optional<GroundPlane> fitGroundToLabels(const OrganizedCloud& cloud_camera,
                                             const std::vector<std::uint8_t>& labels,
                                             const GroundConfig& config);

// Finds the floor in the frame alone, for frames whose camera mount is
// unknown: among the roughly-horizontal planes (normal within max_tilt_deg of
// camera "up", -y) with at least `min_floor_points` supporting points, the
// LOWEST one (furthest below the camera), so a large table top does not win
// over a smaller visible floor. Returns nullopt when no such plane exists
// or it is less than `min_camera_height_m` below the camera.
std::optional<GroundPlane> estimateGround(const OrganizedCloud& cloud_camera,
                                          const NormalImage& normals_camera,
                                          const GroundConfig& config);

}  // namespace findmug
