// findmug/cloud/cloud.hpp — organized point clouds as plain arrays (no PCL here).
//
// The cloud keeps the image grid: point i is pixel (i % width, i / width),
// and an invalid pixel is a NaN point. Keeping the grid is what makes the
// fast organized oversegmenter and label back-projection cheap.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "findmug/frame/frame.hpp"

namespace findmug {

struct OrganizedCloud {
  int width = 0;
  int height = 0;
  std::vector<Eigen::Vector3f> points;  // metres; NaN where depth is invalid
  std::vector<Rgb8> colors;

  std::size_t size() const { return points.size(); }
  bool valid(std::size_t i) const { return std::isfinite(points[i].z()); }
};

// Per-point unit normals on the same grid (NaN where none could be computed).
struct NormalImage {
  int width = 0;
  int height = 0;
  std::vector<Eigen::Vector3f> normals;
};

// Back-projects depth through the pinhole model into the camera optical frame
// (x right, y down, z forward). Zero depth and depth beyond `max_depth_m`
// become NaN. Validates the frame first.
OrganizedCloud frameToCloud(const RgbdFrame& frame, float max_depth_m = 10.0f);

// The variants below that take an `out` argument write the same result into
// it, reusing the memory it already holds (a buffer recycled from an earlier
// frame: no allocation once warm). `out` must not be an input.
void frameToCloud(const RgbdFrame& frame, float max_depth_m, OrganizedCloud& out);

struct NormalConfig {
  int window_radius_px = 4;        // half size of the neighbourhood used per pixel
  float max_depth_jump_m = 0.05f;  // neighbours further than this (scaled by depth) are ignored
  int smoothing_radius_px = 4;     // box average of the per-pixel normals (0 = none)
};

// Normals from the organized grid, oriented towards the camera: cross product
// of the horizontal and vertical differences between the points
// `window_radius_px` away on either side (a neighbour whose depth differs from
// the centre's by more than max_depth_jump_m * depth is skipped, falling back
// to a one-sided difference), then box-averaged over `smoothing_radius_px`.
// NaN where no valid neighbour pair exists.
NormalImage computeNormals(const OrganizedCloud& cloud, const NormalConfig& config);
void computeNormals(const OrganizedCloud& cloud, const NormalConfig& config, NormalImage& out);

// Applies a rigid transform to every valid point (NaNs stay NaN).
OrganizedCloud transformCloud(const OrganizedCloud& cloud, const Eigen::Isometry3f& transform);
NormalImage rotateNormals(const NormalImage& normals, const Eigen::Matrix3f& rotation);
void transformCloud(const OrganizedCloud& cloud, const Eigen::Isometry3f& transform,
                    OrganizedCloud& out);
void rotateNormals(const NormalImage& normals, const Eigen::Matrix3f& rotation, NormalImage& out);

}  // namespace findmug
