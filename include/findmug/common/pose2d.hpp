// findmug/common/pose2d.hpp — the robot base's pose on the floor (x, y, yaw) and what is done with it.
//
// One 2-D pose type for the whole project: the table map places tables with it, and the LCM
// layer's io::RobotPose is a time-stamped Pose2D (robot_pose_t on the wire). The base frame is
// ground aligned, so a pose in a map frame is a position on the floor and a heading.
#pragma once

#include <Eigen/Core>

namespace findmug {

// The base frame's pose in the map: origin position (m) and heading of its
// x axis (rad, counter-clockwise from the map's x axis).
struct Pose2D {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

Pose2D inversePose(const Pose2D& pose);
// a ∘ b: the pose b (given in frame a) expressed in a's parent frame.
Pose2D composePoses(const Pose2D& a, const Pose2D& b);
// A point given in the pose's frame, in the parent frame: R(yaw) * xy + (x, y).
Eigen::Vector2f transformPoint(const Pose2D& pose, const Eigen::Vector2f& xy);
// The same in double precision (what goes on the wire in map-frame messages).
Eigen::Vector2d transformPointD(const Pose2D& pose, const Eigen::Vector2d& xy);
// Angle wrapped to (-pi, pi].
double wrapAngle(double angle);

}  // namespace findmug
