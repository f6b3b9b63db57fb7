// robot_pose_t <-> RobotPose (findmug/io/lcm_codec.hpp).
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "lcm_codec_checks.hpp"

namespace findmug::io {

using detail::checkArraySize;
using detail::checkDimensions;
using detail::checkFinite;
using detail::field;
using detail::finite;

findmug_lcm::robot_pose_t encodeRobotPose(const RobotPose& pose) {
  findmug_lcm::robot_pose_t msg;
  msg.utime = static_cast<std::int64_t>(pose.utime);
  msg.x = pose.pose.x;
  msg.y = pose.pose.y;
  msg.yaw = pose.pose.yaw;
  return msg;
}

RobotPose decodeRobotPose(const void* data, std::size_t size, std::string_view channel) {
  const findmug_lcm::robot_pose_t msg =
      decodeMessage<findmug_lcm::robot_pose_t>(data, size, channel);
  checkFinite({msg.x, msg.y, msg.yaw}, field(channel, "robot_pose_t", "x/y/yaw"));
  if (msg.utime < 0) {
    throw Error(field(channel, "robot_pose_t", "utime") + ": negative time " +
                std::to_string(msg.utime));
  }
  return RobotPose{static_cast<std::uint64_t>(msg.utime), {msg.x, msg.y, msg.yaw}};
}

}  // namespace findmug::io
