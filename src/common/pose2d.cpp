// Pose2D arithmetic (findmug/common/pose2d.hpp).
#include "findmug/common/pose2d.hpp"

#include <cmath>
#include <numbers>

namespace findmug {

double wrapAngle(double angle) {
  constexpr double kPi = std::numbers::pi;
  angle = std::remainder(angle, 2.0 * kPi);  // [-pi, pi]
  return angle <= -kPi ? angle + 2.0 * kPi : angle;
}

Pose2D inversePose(const Pose2D& pose) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return {-(c * pose.x + s * pose.y), -(-s * pose.x + c * pose.y), wrapAngle(-pose.yaw)};
}

Pose2D composePoses(const Pose2D& a, const Pose2D& b) {
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrapAngle(a.yaw + b.yaw)};
}

Eigen::Vector2f transformPoint(const Pose2D& pose, const Eigen::Vector2f& xy) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return Eigen::Vector2f(static_cast<float>(pose.x + c * xy.x() - s * xy.y()),
                         static_cast<float>(pose.y + s * xy.x() + c * xy.y()));
}

Eigen::Vector2d transformPointD(const Pose2D& pose, const Eigen::Vector2d& xy) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return {c * xy.x() - s * xy.y() + pose.x, s * xy.x() + c * xy.y() + pose.y};
}

}  // namespace findmug
