// Robot poses from LCM for the table map; see pose_input.hpp.
#include "findmug/daemon/pose_input.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <lcm/lcm-cpp.hpp>

#include "findmug/error.hpp"

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
    : url_(std::move(url)),
      channel_(std::move(channel)),
      replaying_log_(url_.rfind("file://", 0) == 0),
      on_error_(std::move(on_error)),
      history_(secondsToMicros(history_s)) {
  lcm_ = std::make_unique<lcm::LCM>(url_);
  if (!lcm_->good()) {
    throw Error("daemon.pose_url: cannot open LCM provider '" +
                (url_.empty() ? std::string("<default>") : url_) + "' for " + channel_);
  }
  lcm_->subscribe(channel_, &PoseInput::onMessage, this);
  thread_ = std::thread([this] { run(); });
}

PoseInput::~PoseInput() { stop(); }

void PoseInput::stop() {
  stop_requested_.store(true);
  if (thread_.joinable()) thread_.join();
  lcm_.reset();
}

void PoseInput::run() {
  while (!stop_requested_.load()) {
    // Short timeout: the loop must notice stop() promptly.
    if (lcm_->handleTimeout(100) < 0) {
      if (replaying_log_) {
        spdlog::info("{} ({}): end of pose log after {} poses ({} rejected)", channel_, url_,
                     received_.load(), rejected_.load());
      } else {
        report(channel_ + ": LCM handle for robot poses failed (" + url_ +
               "); no more poses, tables stay in the base frame only");
      }
      break;
    }
  }
  finished_.store(true);
}

void PoseInput::onMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  try {
    const io::RobotPose pose =
        io::decodeRobotPose(buffer->data, static_cast<std::size_t>(buffer->data_size), channel);
    history_.insert(pose);
    received_.fetch_add(1);
  } catch (const std::exception& e) {
    rejected_.fetch_add(1);
    report(std::string("skipping bad robot pose: ") + e.what());
  }
}

void PoseInput::report(const std::string& what) {
  if (on_error_) {
    on_error_(what);
  } else {
    spdlog::warn("{}", what);
  }
}

}  // namespace findmug::daemon
