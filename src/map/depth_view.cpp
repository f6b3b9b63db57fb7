// depth_view.cpp — DepthView: a map point against one depth frame (see the header).
#include "findmug/map/depth_view.hpp"

#include <cmath>
#include <cstdint>

#include "findmug/common/error.hpp"

namespace findmug {

DepthView::DepthView(const RgbdFrame& frame, const Eigen::Isometry3d& camera_in_map)
    : frame_(frame), map_to_camera_(camera_in_map.inverse()), camera_(camera_in_map.translation()) {
  if (frame.width <= 0 || frame.height <= 0 ||
      frame.depth_mm.size() != static_cast<std::size_t>(frame.width) * frame.height)
    throw Error("depth view: frame " + frame.source + " has no depth image of its size");
}

DepthView::Point DepthView::show(const Eigen::Vector3d& point, double hidden_margin_m,
                                 int border_px) const {
  const Eigen::Vector3d q = map_to_camera_ * point;
  if (q.z() <= 0.05) return Point::OutOfView;
  const CameraIntrinsics& k = frame_.intrinsics;
  const double u = k.fx * q.x() / q.z() + k.cx, v = k.fy * q.y() / q.z() + k.cy;
  if (!(std::abs(u) < 1e6 && std::abs(v) < 1e6)) return Point::OutOfView;  // int-safe
  const int pu = static_cast<int>(std::lround(u)), pv = static_cast<int>(std::lround(v));
  if (pu < border_px || pv < border_px || pu >= frame_.width - border_px ||
      pv >= frame_.height - border_px)
    return Point::OutOfView;
  const std::uint16_t d = frame_.depth_mm[static_cast<std::size_t>(pv) * frame_.width + pu];
  if (d == 0) return Point::NoDepth;
  return d * 0.001 < q.z() - hidden_margin_m ? Point::Hidden : Point::Shown;
}

}  // namespace findmug
