// findmug/daemon/pose_input.hpp — the robot's pose in the map, received over LCM.
//
// With a pose, findmugd can give table positions in the map frame and keep
// its persistent table map (findmug/map/table_map.hpp). The pose comes from the
// robot's localisation as findmug_lcm::robot_pose_t on FINDMUG_ROBOT_POSE[_suffix]
// (see lcmtypes/robot_pose_t.lcm); findmugd only listens, it never needs one.
//
//   PoseInput    an io::Subscriber<RobotPose> on its own bus (an LcmBus on
//                daemon.pose_url, or one handed in by a test), whose receive
//                thread owns that bus. Each message is decoded and checked
//                (io::decodeRobotPose); a bad one is reported through the
//                error callback, counted as rejected and skipped.
//   PoseHistory  the poses of the last daemon.pose_history_s seconds, in time
//                order. For a frame the pipeline asks for the pose closest in
//                time to the frame's utime and takes it only when it is at
//                most daemon.pose_max_age_s away: a frame with no pose that
//                recent gets no map-frame positions and does not update the
//                map (a stale pose would put tables in the wrong place).
//
// The lookup happens when a frame is published, i.e. after its segmentation,
// so a pose stamped a little after the frame has normally arrived by then.
// The history must therefore cover the pipeline's latency (default 5 s).
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "findmug/io/bus.hpp"
#include "findmug/io/messages.hpp"
#include "findmug/io/subscriber.hpp"

namespace findmug::daemon {

// Time-indexed poses; thread-safe (the LCM thread inserts, the publish stage
// looks up).
class PoseHistory {
 public:
  // Keeps poses no older than `span_us` before the newest one (and at most
  // kMaxPoses of them, whatever the rate).
  explicit PoseHistory(std::uint64_t span_us);

  static constexpr std::size_t kMaxPoses = 100000;

  // Inserts in time order: a pose that arrives late goes where its utime
  // belongs; one with the utime of a kept pose replaces it.
  void insert(const io::RobotPose& pose);
  // The kept pose whose utime is closest to `utime` (the later one on a tie),
  // when it is at most `max_age_us` away; nullopt otherwise.
  std::optional<io::RobotPose> closest(std::uint64_t utime, std::uint64_t max_age_us) const;
  std::size_t size() const;

 private:
  mutable std::mutex mutex_;
  std::deque<io::RobotPose> poses_;  // increasing utime
  std::uint64_t span_us_;
};

class PoseInput {
 public:
  using OnError = std::function<void(const std::string& what)>;

  // Opens `url` (a file:// log is replayed and ends; anything else is live)
  // and starts the receive thread. Throws findmug::Error naming
  // daemon.pose_url when the provider cannot be opened. `on_error` receives
  // one line per rejected message or provider failure (default: spdlog warning).
  PoseInput(std::string url, std::string channel, double history_s, OnError on_error = {});
  // Listens on `bus` instead (tests: an io::MemoryBus); the pose thread owns it.
  PoseInput(std::shared_ptr<io::Bus> bus, std::string channel, double history_s,
            OnError on_error = {});
  ~PoseInput();
  PoseInput(const PoseInput&) = delete;
  PoseInput& operator=(const PoseInput&) = delete;

  // Stops the thread and closes the handle. Idempotent. The history stays readable.
  void stop();

  const PoseHistory& history() const { return history_; }
  std::uint64_t received() const { return subscriber_->accepted(); }  // accepted poses
  std::uint64_t rejected() const { return subscriber_->rejected(); }  // bad messages skipped
  // The receive loop has ended: end of a replayed log, provider failure, or stop().
  bool finished() const { return subscriber_->finished(); }
  const std::string& url() const { return url_; }
  const std::string& channel() const { return channel_; }

 private:
  void report(const std::string& what);

  std::string url_, channel_;
  OnError on_error_;
  PoseHistory history_;
  std::shared_ptr<io::Bus> bus_;
  std::unique_ptr<io::Subscriber<io::RobotPose>> subscriber_;
};

}  // namespace findmug::daemon
