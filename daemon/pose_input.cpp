// Robot poses from LCM for the table map; see pose_input.hpp.
#include "findmug/daemon/pose_input.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/udpm.hpp"

namespace findmug::daemon {

// ---- PoseHistory ------------------------------------------------------------------

PoseHistory::PoseHistory(std::uint64_t span_us) : span_us_(span_us) {}

void PoseHistory::insert(const io::RobotPose& pose) {
  std::lock_guard lock(mutex_);
  const auto at =
      std::lower_bound(poses_.begin(), poses_.end(), pose.utime,
                       [](const io::RobotPose& p, std::uint64_t utime) { return p.utime < utime; });
  if (at != poses_.end() && at->utime == pose.utime) {
    *at = pose;
  } else {
    poses_.insert(at, pose);
  }
  // Forget what is older than the span before the newest pose.
  const std::uint64_t newest = poses_.back().utime;
  const std::uint64_t oldest_kept = newest > span_us_ ? newest - span_us_ : 0;
  while (!poses_.empty() && poses_.front().utime < oldest_kept) poses_.pop_front();
  while (poses_.size() > kMaxPoses) poses_.pop_front();
}

std::optional<io::RobotPose> PoseHistory::closest(std::uint64_t utime,
                                                  std::uint64_t max_age_us) const {
  std::lock_guard lock(mutex_);
  if (poses_.empty()) return std::nullopt;
  const auto after =
      std::lower_bound(poses_.begin(), poses_.end(), utime,
                       [](const io::RobotPose& p, std::uint64_t t) { return p.utime < t; });
  auto distance = [utime](const io::RobotPose& p) {
    return p.utime > utime ? p.utime - utime : utime - p.utime;
  };
  const io::RobotPose* best = nullptr;
  if (after != poses_.end()) best = &*after;  // the first at or after utime
  if (after != poses_.begin()) {
    const io::RobotPose& before = *std::prev(after);
    if (best == nullptr || distance(before) < distance(*best)) best = &before;
  }
  if (distance(*best) > max_age_us) return std::nullopt;
  return *best;
}

std::size_t PoseHistory::size() const {
  std::lock_guard lock(mutex_);
  return poses_.size();
}

// ---- PoseInput --------------------------------------------------------------------

namespace {
std::uint64_t secondsToMicros(double seconds) {
  return static_cast<std::uint64_t>(std::llround(seconds * 1e6));
}
}  // namespace

PoseInput::PoseInput(std::string url, std::string channel, double history_s, OnError on_error)
    : PoseInput(
          std::shared_ptr<io::Bus>(
              io::openBus(url, "daemon.pose_url (robot poses on " + channel + ")")),
          channel, history_s, std::move(on_error)) {
  url_ = std::move(url);
}

PoseInput::PoseInput(std::shared_ptr<io::Bus> bus, std::string channel, double history_s,
                     OnError on_error)
    : url_(bus->describe()),
      channel_(std::move(channel)),
      on_error_(std::move(on_error)),
      history_(secondsToMicros(history_s)),
      bus_(std::move(bus)) {
  subscriber_ = std::make_unique<io::Subscriber<io::RobotPose>>(
      *bus_, channel_,
      [](const std::uint8_t* data, std::size_t size, const std::string& ch) {
        return io::decodeRobotPose(data, size, ch);
      },
      [this](const io::RobotPose& pose, const std::string&) { history_.insert(pose); },
      [this](const std::string& what) { report("skipping bad robot pose: " + what); });
  subscriber_->startReceiving([this](io::HandleResult how) {
    if (how == io::HandleResult::EndOfLog) {
      spdlog::info("{} ({}): end of pose log after {} poses ({} rejected)", channel_, url_,
                   subscriber_->accepted(), subscriber_->rejected());
    } else {
      report(channel_ + ": LCM handle for robot poses failed (" + url_ +
             "); no more poses, tables stay in the base frame only");
    }
  });
}

PoseInput::~PoseInput() { stop(); }

void PoseInput::stop() {
  subscriber_->stop();
  // Close the handle (leaves a udpm group); the counters stay readable.
  bus_.reset();
}

void PoseInput::report(const std::string& what) {
  if (on_error_) {
    on_error_(what);
  } else {
    spdlog::warn("{}", what);
  }
}

}  // namespace findmug::daemon
