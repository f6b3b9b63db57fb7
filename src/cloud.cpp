// cloud.cpp — depth back-projection, organized-grid normals, rigid transforms.
//
// Normals: a pixel's normal is the cross product of a horizontal and a
// vertical tangent, each the difference between the points `window_radius_px`
// pixels to either side (central difference, or one-sided where a neighbour is
// missing or lies across a depth discontinuity). Those raw normals are then
// averaged over a small box (half the window radius) to beat down Kinect depth
// quantisation, which at 3 m is a few centimetres per step and would otherwise
// tilt single-difference normals by tens of degrees. Everything is O(1) per
// pixel with separable running sums, so a 640x480 frame costs a few
// milliseconds on one core.
#include "findmug/cloud.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "findmug/error.hpp"

namespace findmug {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
const Eigen::Vector3f kNaNVector(kNaN, kNaN, kNaN);

void checkCloudShape(const OrganizedCloud& cloud, const char* what) {
  const auto pixels = static_cast<std::size_t>(std::max(cloud.width, 0)) *
                      static_cast<std::size_t>(std::max(cloud.height, 0));
  if (cloud.width <= 0 || cloud.height <= 0 || cloud.points.size() != pixels) {
    std::ostringstream msg;
    msg << what << ": organized cloud is " << cloud.width << "x" << cloud.height << " but holds "
        << cloud.points.size() << " points";
    throw Error(msg.str());
  }
  if (!cloud.colors.empty() && cloud.colors.size() != pixels) {
    std::ostringstream msg;
    msg << what << ": organized cloud has " << cloud.colors.size() << " colours for "
        << pixels << " points";
    throw Error(msg.str());
  }
}

// Tangent along one image axis at pixel `c`, from neighbours `a` (before) and
// `b` (after). A neighbour counts when it is valid and its depth is within
// `max_jump` of the centre's. Returns false when no tangent is possible.
inline bool tangent(const Eigen::Vector3f& a, const Eigen::Vector3f& c, const Eigen::Vector3f& b,
                    float max_jump, Eigen::Vector3f& out) {
  const bool a_ok = std::isfinite(a.z()) && std::abs(a.z() - c.z()) <= max_jump;
  const bool b_ok = std::isfinite(b.z()) && std::abs(b.z() - c.z()) <= max_jump;
  if (a_ok && b_ok) {
    out = b - a;
  } else if (b_ok) {
    out = b - c;
  } else if (a_ok) {
    out = c - a;
  } else {
    return false;
  }
  return true;
}

// Box sums (radius r, clipped at the border) of the finite entries of `in`,
// separably: rows into `tmp` with a prefix sum, then columns into `out` with
// one running sum per column, so every pixel costs O(1) and no full-size
// prefix table is needed. Non-finite entries count as zero.
void boxSum(const std::vector<Eigen::Vector3f>& in, int width, int height, int r,
            std::vector<Eigen::Vector3f>& tmp, std::vector<Eigen::Vector3f>& out) {
  tmp.resize(in.size());
  out.resize(in.size());
  std::vector<Eigen::Vector3f> prefix(static_cast<std::size_t>(width) + 1);
  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* row = in.data() + static_cast<std::size_t>(v) * width;
    Eigen::Vector3f* dst = tmp.data() + static_cast<std::size_t>(v) * width;
    prefix[0].setZero();
    for (int u = 0; u < width; ++u)
      prefix[u + 1] = prefix[u] + (std::isfinite(row[u].x()) ? row[u] : Eigen::Vector3f::Zero());
    for (int u = 0; u < width; ++u)
      dst[u] = prefix[std::min(width, u + r + 1)] - prefix[std::max(0, u - r)];
  }
  std::vector<Eigen::Vector3f> column(static_cast<std::size_t>(width), Eigen::Vector3f::Zero());
  // Prime with rows 0..r-1; each output row v then adds row v+r, drops v-r-1.
  for (int v = 0; v < std::min(r, height); ++v) {
    const Eigen::Vector3f* src = tmp.data() + static_cast<std::size_t>(v) * width;
    for (int u = 0; u < width; ++u) column[u] += src[u];
  }
  for (int v = 0; v < height; ++v) {
    if (v + r < height) {
      const Eigen::Vector3f* add = tmp.data() + static_cast<std::size_t>(v + r) * width;
      for (int u = 0; u < width; ++u) column[u] += add[u];
    }
    if (v - r - 1 >= 0) {
      const Eigen::Vector3f* drop = tmp.data() + static_cast<std::size_t>(v - r - 1) * width;
      for (int u = 0; u < width; ++u) column[u] -= drop[u];
    }
    std::copy(column.begin(), column.end(), out.begin() + static_cast<std::ptrdiff_t>(v) * width);
  }
}

}  // namespace

OrganizedCloud frameToCloud(const RgbdFrame& frame, float max_depth_m) {
  validateFrame(frame);
  if (!std::isfinite(max_depth_m) || max_depth_m <= 0.0f) {
    throw Error((frame.source.empty() ? std::string("frameToCloud") : frame.source) +
                ": invalid max_depth_m " + std::to_string(max_depth_m));
  }
  OrganizedCloud cloud;
  cloud.width = frame.width;
  cloud.height = frame.height;
  const std::size_t pixels = static_cast<std::size_t>(frame.width) * frame.height;
  cloud.points.resize(pixels);
  cloud.colors = frame.rgb;

  const auto& k = frame.intrinsics;
  const float inv_fx = static_cast<float>(1.0 / k.fx);
  const float inv_fy = static_cast<float>(1.0 / k.fy);
  const float cx = static_cast<float>(k.cx);
  const float cy = static_cast<float>(k.cy);
  // Compare in millimetres so the hot loop has no float conversion for
  // rejected pixels.
  const double max_mm = static_cast<double>(max_depth_m) * 1000.0;

  for (int v = 0; v < frame.height; ++v) {
    const float ray_y = (static_cast<float>(v) - cy) * inv_fy;
    const std::size_t row = static_cast<std::size_t>(v) * frame.width;
    for (int u = 0; u < frame.width; ++u) {
      const std::uint16_t d = frame.depth_mm[row + u];
      if (d == 0 || d > max_mm) {
        cloud.points[row + u] = kNaNVector;
        continue;
      }
      const float z = static_cast<float>(d) * 0.001f;
      const float ray_x = (static_cast<float>(u) - cx) * inv_fx;
      cloud.points[row + u] = Eigen::Vector3f(ray_x * z, ray_y * z, z);
    }
  }
  return cloud;
}

NormalImage computeNormals(const OrganizedCloud& cloud, const NormalConfig& config) {
  checkCloudShape(cloud, "computeNormals");
  if (config.window_radius_px < 1 || config.window_radius_px > 64) {
    throw Error("computeNormals: normals.window_radius_px must be in 1..64, got " +
                std::to_string(config.window_radius_px));
  }
  if (!std::isfinite(config.max_depth_jump_m) || config.max_depth_jump_m <= 0.0f) {
    throw Error("computeNormals: normals.max_depth_jump_m must be positive, got " +
                std::to_string(config.max_depth_jump_m));
  }
  const int w = cloud.width;
  const int h = cloud.height;
  const int r = config.window_radius_px;
  const Eigen::Vector3f* pts = cloud.points.data();

  NormalImage out;
  out.width = w;
  out.height = h;
  out.normals.assign(cloud.points.size(), kNaNVector);
  std::vector<Eigen::Vector3f>& n = out.normals;

  // 1. Raw normals from differences at +-r pixels, oriented towards the
  //    camera (the optical centre is the origin, so n.dot(p) < 0).
  for (int v = 0; v < h; ++v) {
    const int v_up = std::max(0, v - r);
    const int v_down = std::min(h - 1, v + r);
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      const Eigen::Vector3f& c = pts[i];
      if (!std::isfinite(c.z())) continue;
      // The tolerated depth step grows with depth: both the sensor noise and
      // the depth change across r pixels of an oblique surface do.
      const float max_jump = config.max_depth_jump_m * c.z();
      const int u_left = std::max(0, u - r);
      const int u_right = std::min(w - 1, u + r);
      Eigen::Vector3f th, tv;
      if (!tangent(pts[static_cast<std::size_t>(v) * w + u_left], c,
                   pts[static_cast<std::size_t>(v) * w + u_right], max_jump, th) ||
          !tangent(pts[static_cast<std::size_t>(v_up) * w + u], c,
                   pts[static_cast<std::size_t>(v_down) * w + u], max_jump, tv)) {
        continue;
      }
      Eigen::Vector3f normal = th.cross(tv);
      const float norm = normal.norm();
      if (!(norm > 0.0f)) continue;
      normal /= norm;
      if (normal.dot(c) > 0.0f) normal = -normal;
      n[i] = normal;
    }
  }

  // 2. Box-average the raw normals (radius r/2) and renormalise. Pixels that
  //    had no raw normal stay NaN: they are isolated or on a depth edge.
  const int smooth_r = r / 2;
  if (smooth_r > 0) {
    std::vector<Eigen::Vector3f> tmp, smoothed;
    boxSum(n, w, h, smooth_r, tmp, smoothed);
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (!std::isfinite(n[i].x())) continue;
      const float norm = smoothed[i].norm();
      // The raw normal itself is in the sum, but opposite neighbours can
      // cancel it on a thin ridge; keep the raw one then.
      if (norm > 1e-3f) n[i] = smoothed[i] / norm;
    }
  }
  return out;
}

OrganizedCloud transformCloud(const OrganizedCloud& cloud, const Eigen::Isometry3f& transform) {
  OrganizedCloud out;
  out.width = cloud.width;
  out.height = cloud.height;
  out.colors = cloud.colors;
  out.points.resize(cloud.points.size());
  const Eigen::Matrix3f rotation = transform.linear();
  const Eigen::Vector3f translation = transform.translation();
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    out.points[i] = std::isfinite(p.z()) ? Eigen::Vector3f(rotation * p + translation) : kNaNVector;
  }
  return out;
}

NormalImage rotateNormals(const NormalImage& normals, const Eigen::Matrix3f& rotation) {
  NormalImage out;
  out.width = normals.width;
  out.height = normals.height;
  out.normals.resize(normals.normals.size());
  for (std::size_t i = 0; i < normals.normals.size(); ++i) {
    const Eigen::Vector3f& n = normals.normals[i];
    out.normals[i] = std::isfinite(n.x()) ? Eigen::Vector3f(rotation * n) : kNaNVector;
  }
  return out;
}

}  // namespace findmug
