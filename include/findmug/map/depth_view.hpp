// findmug/map/depth_view.hpp — what one depth frame, taken from a known camera pose, shows
// of a point of the map: out of view, no depth there, hidden behind something nearer, or
// shown.
//
// Why: two parts of the map reason about what a view could have shown. The table map must
// not count a table as missing when a wall or a cabinet stood between it and the camera
// (absence of evidence where the view was blocked is no evidence of absence), and the
// table-top memory must not count a top as searched where an object hid it. Both project a
// map point into the depth image and compare depths; this does it once.
//
// Pure core code: no LCM, no clock, no threads.
#pragma once

#include <Eigen/Geometry>

#include "findmug/frame/frame.hpp"

namespace findmug {

class DepthView {
 public:
  enum class Point {
    OutOfView,  // behind the camera, or projecting outside the image (less its border)
    NoDepth,    // no valid depth at its pixel
    Hidden,     // the depth there is nearer than the point by more than the margin
    Shown,      // the depth there reaches the point (or passes it: nothing in front)
  };

  // `frame` must outlive the view. Throws findmug::Error (naming the frame's source) when
  // the frame has no depth image of its size.
  DepthView(const RgbdFrame& frame, const Eigen::Isometry3d& camera_in_map);

  // How the view shows `point` (map frame): see Point. Pixels within `border_px` of the
  // image edge count as out of view.
  Point show(const Eigen::Vector3d& point, double hidden_margin_m, int border_px) const;

  const Eigen::Vector3d& cameraPosition() const { return camera_; }

 private:
  const RgbdFrame& frame_;
  Eigen::Isometry3d map_to_camera_;
  Eigen::Vector3d camera_;
};

}  // namespace findmug
