// tests/support/table_scenes.hpp — mapped tables and what a robot's head
// camera sees of them, for the tests of the map room and the daemon's find
// and map sinks.
//
// tableAt makes a mapped table of a fixed size (1.2 x 0.8 m, top 0.75 m up)
// with its hull; withSearchPositions adds one search position on each long
// side. headCamera is the camera of a robot whose head is 1.2 m up and
// pitched 0.5 rad down. depthOfTops renders a depth image in which every ray
// meets a table top (inside a table's hull) or the floor, nothing else: what
// TableTopViews' visibility test needs, without the renderer of src/synth.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <vector>

#include "findmug/frame/frame.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/common/pose2d.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug::test {

inline constexpr float kTableTopZ = 0.75f;

// A mapped table centred at (cx, cy): 1.2 m along x, 0.8 m along y.
inline TableCluster tableAt(float cx, float cy, int id = 0) {
  TableCluster t;
  t.id = id;
  t.top_height = kTableTopZ;
  t.centroid = {cx, cy, kTableTopZ};
  t.center = {cx, cy};
  t.extents = {0.6f, 0.4f};
  t.hull = {{cx - 0.6f, cy - 0.4f}, {cx + 0.6f, cy - 0.4f}, {cx + 0.6f, cy + 0.4f},
            {cx - 0.6f, cy + 0.4f}};
  return t;
}

// The table with a search position 0.9 m from its centre on each long side,
// facing it (north first).
inline TableCluster withSearchPositions(TableCluster t) {
  SearchPosition north, south;
  north.xy = {t.center.x(), t.center.y() + 0.9f};
  north.yaw = static_cast<float>(-M_PI / 2);
  south.xy = {t.center.x(), t.center.y() - 0.9f};
  south.yaw = static_cast<float>(M_PI / 2);
  t.search_positions = {north, south};
  return t;
}

// The mount of the robot's head camera: 1.2 m up, 0.5 rad down.
inline CameraExtrinsics headMount() {
  CameraExtrinsics mount;
  mount.height_m = 1.2;
  mount.pitch_rad = 0.5;
  return mount;
}

// The head camera in the map frame of a robot at `robot`.
inline Eigen::Isometry3d headCamera(const Pose2D& robot) {
  return cameraInMap(robot, groundFromExtrinsics(headMount()).camera_to_ground);
}

inline bool insideHull(const TableCluster& table, const Eigen::Vector2d& p) {
  for (std::size_t i = 0; i < table.hull.size(); ++i) {
    const Eigen::Vector2d a = table.hull[i].cast<double>();
    const Eigen::Vector2d b = table.hull[(i + 1) % table.hull.size()].cast<double>();
    if ((b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x()) < 0) return false;
  }
  return !table.hull.empty();
}

// A 640x480 frame seen from `camera` (map frame, z up, floor at 0): depth of
// the table tops at `top_z` where a ray meets one inside its hull, else of the
// floor; 0 for rays that never meet the floor. RGB black.
inline RgbdFrame depthOfTops(const std::vector<TableCluster>& tables,
                             const Eigen::Isometry3d& camera, double top_z = kTableTopZ) {
  RgbdFrame f;
  f.width = 640;
  f.height = 480;
  f.source = "table tops and floor";
  f.depth_mm.assign(640 * 480, 0);
  f.rgb.assign(640 * 480, Rgb8{});
  const Eigen::Vector3d origin = camera.translation();
  for (int v = 0; v < f.height; ++v) {
    for (int u = 0; u < f.width; ++u) {
      const Eigen::Vector3d dir =
          camera.linear() * Eigen::Vector3d((u - f.intrinsics.cx) / f.intrinsics.fx,
                                            (v - f.intrinsics.cy) / f.intrinsics.fy, 1.0);
      if (dir.z() >= -1e-9) continue;  // never meets the floor
      double t = -origin.z() / dir.z();  // the floor
      const double on_top = (top_z - origin.z()) / dir.z();
      const Eigen::Vector3d p = origin + on_top * dir;
      for (const TableCluster& table : tables)
        if (insideHull(table, p.head<2>())) t = on_top;
      f.depth_mm[v * f.width + u] = static_cast<std::uint16_t>(std::lround(t * 1000.0));
    }
  }
  return f;
}

}  // namespace findmug::test
