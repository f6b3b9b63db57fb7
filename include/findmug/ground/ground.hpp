// findmug/ground/ground.hpp — the ground plane and the ground-aligned frame.
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

#include "findmug/cloud/cloud.hpp"
#include "findmug/frame/frame.hpp"

namespace findmug {

// How a frame's ground plane was obtained (reported per frame by
// findmug-train and findmug-eval; groundMethodName gives the spelling).
enum class GroundMethod {
  Given,                 // "plane": built by groundFromPlane from a caller's plane
  Extrinsics,            // "extrinsics": the camera mount
  FloorLabels,           // "floor_labels": RANSAC plane on ground-truth floor pixels
  Estimated,             // "estimated": lowest horizontal plane, frame alone
  GravityFloorLabels,    // "gravity+floor_labels": gravity, height of the labelled floor
  GravityLowestPlane,    // "gravity+lowest_plane": gravity, lowest supported horizontal surface
  GravityLowPercentile,  // "gravity+low_percentile": gravity, low percentile of all heights
                         // (no horizontal surface low enough to be the floor)
  GravityHeightPrior,    // "gravity+height_prior": gravity, floor out of view: nothing reaches
                         // prior_camera_height_m below the camera, so the floor is put there
};
const char* groundMethodName(GroundMethod method);

struct GroundPlane {
  // Plane in the camera frame: normal.dot(p) + offset = 0, normal unit and
  // pointing up (away from the floor, towards the camera side).
  Eigen::Vector3f normal_camera = Eigen::Vector3f(0, -1, 0);
  float offset = 0.0f;
  // Maps camera-frame points into the ground-aligned frame.
  Eigen::Isometry3f camera_to_ground = Eigen::Isometry3f::Identity();
  int support_points = 0;  // inliers that produced it (0 when from extrinsics)
  GroundMethod method = GroundMethod::Given;
};

enum class GroundSource {
  Auto,          // extrinsics when the frame carries them, else Estimated
  Extrinsics,    // from the camera mount (robot); a frame without them is an error
  FloorLabels,   // RANSAC on ground-truth floor pixels (the paper's protocol)
  Estimated,     // dominant horizontal plane found in the frame alone
  // Per-frame gravity (RgbdFrame::gravity_up, e.g. NYU's rotations) gives
  // "up"; the floor height along it comes from the labelled floor when it
  // has min_floor_points points, else from the frame (groundFromGravity).
  // A frame with extrinsics uses them (a robot knows both); a frame without
  // gravity falls back to FloorLabels (if labels were given), then Estimated.
  Gravity,
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
  // groundFromGravity without floor labels: the floor is taken no higher
  // than this percentile (in %) of all point heights along gravity, ...
  float floor_percentile = 1.0f;
  // ... i.e. when that percentile lies more than this below the lowest
  // supported horizontal surface, that surface is a table or seat and the
  // floor is at the percentile (cabinet fronts, chair legs and walls reach
  // down to a floor hidden behind furniture).
  float percentile_margin_m = 0.15f;
  // groundFromGravity: a floor plane fitted to the labelled floor (or to the
  // lowest horizontal surface) whose normal is within this angle of the given
  // gravity replaces it; 0 = always keep the given direction. NYU's
  // rotations differ from the labelled floor's normal by 0.8..6.4 degrees.
  float gravity_refine_deg = 8.0f;
  // groundFromGravity, floor out of view: the camera is taken this high above
  // it. The median over the NYU labelled frames whose floor is labelled
  // (17 frames, 0.82..1.41 m, median 1.28 m; perf-log §1d).
  float prior_camera_height_m = 1.28f;
  // A stream of frames from one mount (a GroundTracker, ground_tracker.hpp, with
  // the floor estimated from the frame): the floor found in one frame is kept for the
  // next ones while confirmGround finds that it still holds at least
  // `reuse_min_support_fraction` of the support it had, and re-estimated at
  // the latest every `reestimate_every_frames` frames. 1 = estimate in every
  // frame (the paper; what evaluation on independent frames needs).
  int reestimate_every_frames = 1;
  float reuse_min_support_fraction = 0.8f;
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

// Whether `previous` (a plane from estimateGround on an earlier frame of the
// same mount) is still this frame's floor: its support, counted as
// estimateGround counts it (within ransac_inlier_m, normal within
// max_tilt_deg of camera up and normal_agreement_deg of the plane) on every
// fourth pixel of every fourth row and scaled by 16, must reach
// min_floor_points and reuse_min_support_fraction x previous.support_points.
// Returns `previous` with support_points set to this frame's count, or
// nullopt (then estimate again). About 1/20 of estimateGround's cost.
std::optional<GroundPlane> confirmGround(const OrganizedCloud& cloud_camera,
                                         const NormalImage& normals_camera,
                                         const GroundPlane& previous, const GroundConfig& config);

// The ground frame from a known "up" direction (unit, camera coordinates,
// against gravity) and the floor height along it:
//  1. `labels` given (same grid as the cloud) with at least
//     `min_floor_points` valid Floor pixels: their RANSAC plane
//     (fitGroundToLabels) when its normal is within `gravity_refine_deg` of
//     up, else the median height of those points along up (GravityFloorLabels);
//  2. else estimateGround's plane when its normal is within
//     `gravity_refine_deg` of up and the `floor_percentile` % height of all
//     points is not more than `percentile_margin_m` below it
//     (GravityLowestPlane); else the lowest
//     horizontal surface along up: heights of the points whose
//     normal is within `normal_agreement_deg` of up, binned by
//     `ransac_inlier_m`; the lowest level holding `min_floor_points` points
//     within +-ransac_inlier_m, if it is at least `min_camera_height_m`
//     below the camera (GravityLowestPlane; its least-squares plane replaces
//     up when within `gravity_refine_deg`) — unless the `floor_percentile` %
//     height of all points lies more than `percentile_margin_m` below it;
//  3. else that percentile when it is at least `prior_camera_height_m` below
//     the camera (GravityLowPercentile: furniture reaching down to a floor
//     hidden behind it), else `prior_camera_height_m` (GravityHeightPrior).
// Returns nullopt only when the cloud has no valid point or every point is
// above the camera (no floor below it). Heights are up.dot(p) in metres.
std::optional<GroundPlane> groundFromGravity(const OrganizedCloud& cloud_camera,
                                             const NormalImage& normals_camera,
                                             const Eigen::Vector3f& up_camera,
                                             const std::vector<std::uint8_t>* labels,
                                             const GroundConfig& config);

}  // namespace findmug
