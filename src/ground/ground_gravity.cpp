// ground_gravity.cpp — the ground plane from a known gravity direction (an IMU, or NYU's
// camera rotations): the floor's height along "up", from floor labels, the lowest
// horizontal level or the usual camera height (see ground.hpp, groundFromGravity).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/ground/ground.hpp"
#include "ground/ground_internal.hpp"

namespace findmug {

using detail::cosDeg;
using detail::kSameLevelM;
using detail::Plane;
using detail::quantile;
using detail::refitPlane;
using detail::validateConfig;

namespace {

constexpr std::uint8_t kFloorLabelId = static_cast<std::uint8_t>(Label::Floor);

// groundFromGravity's inputs checked; returns up_camera as a unit vector.
Eigen::Vector3f checkedGravityUp(const OrganizedCloud& cloud_camera,
                                 const NormalImage& normals_camera,
                                 const Eigen::Vector3f& up_camera,
                                 const std::vector<std::uint8_t>* labels) {
  const float up_norm = up_camera.norm();
  if (!std::isfinite(up_norm) || !(up_norm > 1e-6f)) {
    std::ostringstream msg;
    msg << "groundFromGravity: unusable up direction (" << up_camera.transpose() << ")";
    throw Error(msg.str());
  }
  if (normals_camera.normals.size() != cloud_camera.points.size()) {
    throw Error("groundFromGravity: normal image has " +
                std::to_string(normals_camera.normals.size()) + " entries but the cloud has " +
                std::to_string(cloud_camera.points.size()) + " points");
  }
  if (labels && labels->size() != cloud_camera.points.size()) {
    throw Error("groundFromGravity: label image has " + std::to_string(labels->size()) +
                " pixels but the cloud has " + std::to_string(cloud_camera.points.size()));
  }
  return up_camera / up_norm;
}

// The ground plane with normal `up` through the floor at `floor_height`
// (along up, camera at 0), or nullopt when that is not below the camera
// (plane up.p + d = 0 needs d > 0).
std::optional<GroundPlane> groundAtHeight(const Eigen::Vector3f& up, float floor_height,
                                          GroundMethod method, std::size_t support) {
  const float offset = -floor_height;
  if (!(offset > 1e-3f)) return std::nullopt;
  GroundPlane ground = groundFromPlane(up, offset, static_cast<int>(support));
  ground.method = method;
  return ground;
}

// A floor height along up and the points it rests on.
struct FloorHeight {
  float height = 0.0f;
  std::size_t support = 0;
};

// The median height of the labelled floor's pixels, when there are at least
// `min_points`: robust to mislabelled pixels at object feet; a gravity
// direction off by a degree or two only widens the spread around it.
std::optional<FloorHeight> labelledFloorHeight(const OrganizedCloud& cloud_camera,
                                               const std::vector<std::uint8_t>& labels,
                                               const Eigen::Vector3f& up, std::size_t min_points) {
  const auto& pts = cloud_camera.points;
  std::vector<float> floor;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (labels[i] == kFloorLabelId && cloud_camera.valid(i)) floor.push_back(up.dot(pts[i]));
  if (floor.size() < min_points) return std::nullopt;
  return FloorHeight{quantile(floor, 0.5), floor.size()};
}

// The frame's own lowest horizontal plane (estimateGround: sequential
// RANSAC, consistent "up" across surfaces) when it agrees with gravity: a
// histogram of heights along a gravity that is a few degrees off smears a
// large floor over many bins, while the plane fit is not affected. As in
// groundFromHeights, it is not the floor when a low percentile of all
// points lies well beneath it (a bed or table top seen above a hidden floor).
std::optional<GroundPlane> lowestPlaneAlongGravity(const OrganizedCloud& cloud_camera,
                                                   const NormalImage& normals_camera,
                                                   const Eigen::Vector3f& up,
                                                   const GroundConfig& config) {
  const auto& pts = cloud_camera.points;
  auto estimated = estimateGround(cloud_camera, normals_camera, config);
  if (!estimated || !(estimated->normal_camera.dot(up) >= cosDeg(config.gravity_refine_deg))) {
    return std::nullopt;
  }
  std::vector<float> heights;
  heights.reserve(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (cloud_camera.valid(i)) heights.push_back(estimated->normal_camera.dot(pts[i]));
  const float low = quantile(heights, config.floor_percentile / 100.0);
  if (!(low >= -estimated->offset - config.percentile_margin_m)) return std::nullopt;
  estimated->method = GroundMethod::GravityLowestPlane;
  return estimated;
}

// The lowest level of the heights of horizontal points, and the band of
// heights [lo, hi) it spans.
struct HorizontalLevel {
  float height = 0.0f;
  std::size_t support = 0;
  float lo = 0.0f, hi = 0.0f;
};

// Bins of `bin` metres; a level counts the points of its bin and both
// neighbours (a slightly wrong gravity or a slightly sloped floor spreads
// one surface over ~3 bins). The lowest level with min_points, moved to the
// densest level within kSameLevelM above it; its height is the mean of the
// points in the level's three bins. `horizontal` holds at least min_points.
std::optional<HorizontalLevel> lowestHorizontalLevel(const std::vector<float>& horizontal,
                                                     std::size_t min_points, float bin) {
  const auto [lo_it, hi_it] = std::minmax_element(horizontal.begin(), horizontal.end());
  const float lo = *lo_it;
  const auto bins = static_cast<std::size_t>((*hi_it - lo) / bin) + 1;
  std::vector<std::size_t> count(bins, 0);
  for (float h : horizontal) ++count[std::min(bins - 1, static_cast<std::size_t>((h - lo) / bin))];
  auto level = [&](std::size_t b) {
    return count[b] + (b > 0 ? count[b - 1] : 0) + (b + 1 < bins ? count[b + 1] : 0);
  };
  for (std::size_t b = 0; b < bins; ++b) {
    if (level(b) < min_points) continue;
    // The surface is the densest level within kSameLevelM above.
    std::size_t best = b;
    const auto reach = static_cast<std::size_t>(kSameLevelM / bin);
    for (std::size_t c = b + 1; c < bins && c <= b + reach; ++c)
      if (level(c) > level(best)) best = c;
    // Its height: the mean of the points in the level's three bins.
    double sum = 0;
    std::size_t n = 0;
    for (float h : horizontal) {
      const float rel = (h - lo) / bin;
      if (rel >= static_cast<float>(best) - 1.0f && rel < static_cast<float>(best) + 2.0f) {
        sum += h;
        ++n;
      }
    }
    return HorizontalLevel{static_cast<float>(sum / static_cast<double>(n)), n,
                           lo + bin * (static_cast<float>(best) - 1.0f),
                           lo + bin * (static_cast<float>(best) + 2.0f)};
  }
  return std::nullopt;
}

// The least-squares plane of the level's horizontal points, when it agrees
// with gravity, as for the labelled floor, and puts the floor where the
// level is at the camera (a tilted fit of a far, small surface may not).
std::optional<GroundPlane> fittedLevelPlane(const OrganizedCloud& cloud_camera,
                                            const NormalImage& normals_camera,
                                            const Eigen::Vector3f& up, const HorizontalLevel& level,
                                            const GroundConfig& config) {
  const auto& pts = cloud_camera.points;
  const auto& nrm = normals_camera.normals;
  const float cos_agree = cosDeg(config.normal_agreement_deg);
  std::vector<Eigen::Vector3f> points;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!cloud_camera.valid(i) || !std::isfinite(nrm[i].x()) || nrm[i].dot(up) < cos_agree)
      continue;
    const float h = up.dot(pts[i]);
    if (h >= level.lo && h < level.hi) points.push_back(pts[i]);
  }
  std::vector<std::size_t> idx(points.size());
  for (std::size_t k = 0; k < idx.size(); ++k) idx[k] = k;
  Plane hint;
  hint.normal = up;
  Plane fitted = hint;  // offset 0: rejected below unless the fit runs
  if (idx.size() >= 3) fitted = refitPlane(points, idx, hint);
  if (!(fitted.normal.dot(up) >= cosDeg(config.gravity_refine_deg) &&
        std::abs(fitted.offset + level.height) <= kSameLevelM)) {
    return std::nullopt;
  }
  GroundPlane ground =
      groundFromPlane(fitted.normal, fitted.offset, static_cast<int>(level.support));
  ground.method = GroundMethod::GravityLowestPlane;
  return ground;
}

// The floor from the heights of the frame's points along gravity alone
// (steps 2 and 3 of groundFromGravity in ground.hpp): the lowest horizontal
// level, else a low percentile of all heights, else the height prior.
std::optional<GroundPlane> groundFromHeights(const OrganizedCloud& cloud_camera,
                                             const NormalImage& normals_camera,
                                             const Eigen::Vector3f& up,
                                             const GroundConfig& config) {
  const auto& pts = cloud_camera.points;
  const auto& nrm = normals_camera.normals;
  const auto min_points = static_cast<std::size_t>(config.min_floor_points);
  const float cos_agree = cosDeg(config.normal_agreement_deg);
  std::vector<float> all;
  std::vector<float> horizontal;
  all.reserve(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!cloud_camera.valid(i)) continue;
    const float h = up.dot(pts[i]);
    all.push_back(h);
    if (std::isfinite(nrm[i].x()) && nrm[i].dot(up) >= cos_agree) horizontal.push_back(h);
  }
  if (all.empty()) return std::nullopt;
  const float low = quantile(all, config.floor_percentile / 100.0);
  const std::optional<HorizontalLevel> level =
      horizontal.size() >= min_points
          ? lowestHorizontalLevel(horizontal, min_points, config.ransac_inlier_m)
          : std::nullopt;
  // A surface less than min_camera_height_m below the camera is a table
  // or seat seen without the floor (see GroundConfig), not the floor.
  if (level && -level->height >= config.min_camera_height_m &&
      low >= level->height - config.percentile_margin_m) {
    if (config.gravity_refine_deg > 0.0f) {
      if (auto fitted = fittedLevelPlane(cloud_camera, normals_camera, up, *level, config)) {
        return fitted;
      }
    }
    return groundAtHeight(up, level->height, GroundMethod::GravityLowestPlane, level->support);
  }
  if (-low >= config.prior_camera_height_m) {
    return groundAtHeight(up, low, GroundMethod::GravityLowPercentile, all.size());
  }
  // Nothing in view reaches as low as a typical floor: the floor is out
  // of view, and at least the usual camera height below.
  return groundAtHeight(up, -config.prior_camera_height_m, GroundMethod::GravityHeightPrior, 0);
}

}  // namespace

std::optional<GroundPlane> groundFromGravity(const OrganizedCloud& cloud_camera,
                                             const NormalImage& normals_camera,
                                             const Eigen::Vector3f& up_camera,
                                             const std::vector<std::uint8_t>* labels,
                                             const GroundConfig& config) {
  validateConfig(config, "groundFromGravity");
  const Eigen::Vector3f up = checkedGravityUp(cloud_camera, normals_camera, up_camera, labels);
  // The labelled floor's own plane, when it agrees with gravity: measured
  // gravity (NYU's rotations) is off by up to ~6 degrees on some frames,
  // which would tilt heights by ~0.4 m at 4 m, while the floor plane is what
  // height features are measured from (the paper's protocol).
  if (labels && config.gravity_refine_deg > 0.0f) {
    if (auto fit = fitGroundToLabels(cloud_camera, *labels, config);
        fit && fit->normal_camera.dot(up) >= cosDeg(config.gravity_refine_deg)) {
      fit->method = GroundMethod::GravityFloorLabels;
      return fit;
    }
  }
  if (labels) {
    const auto min_points = static_cast<std::size_t>(config.min_floor_points);
    if (const auto floor = labelledFloorHeight(cloud_camera, *labels, up, min_points)) {
      return groundAtHeight(up, floor->height, GroundMethod::GravityFloorLabels, floor->support);
    }
  }
  if (config.gravity_refine_deg > 0.0f) {
    if (auto plane = lowestPlaneAlongGravity(cloud_camera, normals_camera, up, config)) {
      return plane;
    }
  }
  return groundFromHeights(cloud_camera, normals_camera, up, config);
}

}  // namespace findmug
