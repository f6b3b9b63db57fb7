// findmug/daemon/service.hpp — living under systemd: notify protocol, watchdog, logging.
//
// Notify protocol (Type=notify): READY=1 once the model is loaded and the
// source is open; STOPPING=1 when shutdown begins; STATUS=... lines for
// `systemctl status`. Messages go to $NOTIFY_SOCKET through libsystemd's
// sd_notify; without it (started by hand) they are no-ops.
//
// Watchdog (WatchdogSec=): systemd restarts the service unless WATCHDOG=1
// arrives in time. A free-running timer thread would keep a wedged daemon
// alive, so pings are gated on evidence that the pipeline works:
//
//   * the source thread came round its loop recently (it wakes at least every
//     source poll timeout even with no frames, so an idle camera, a
//     reconnecting device or a quiet LCM channel still counts as alive, but a
//     thread hung inside a driver call does not), AND
//   * either nothing is waiting in the pipeline (idle), or frames have left
//     the segmentation/publish stages recently. Frames merely being DROPPED
//     at a full queue do not count: a stuck worker with a flooding source
//     must not look healthy.
//
// "Recently" is the stall limit, by default half of WatchdogSec, and pings
// are sent every third of WatchdogSec while healthy, so a stall is caught
// within 1.5 × WatchdogSec at most.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace findmug::daemon {

class SystemdNotifier {
 public:
  // Reads $NOTIFY_SOCKET and $WATCHDOG_USEC ($WATCHDOG_PID must match if set).
  SystemdNotifier();

  bool enabled() const { return enabled_; }
  // WatchdogSec as passed by systemd, when the watchdog is on.
  std::optional<std::chrono::microseconds> watchdogTimeout() const { return watchdog_; }

  void ready(const std::string& status) const;
  void watchdog() const;
  void stopping(const std::string& status) const;
  void status(const std::string& status) const;

 private:
  void send(const std::string& message) const;
  bool enabled_ = false;
  std::optional<std::chrono::microseconds> watchdog_;
};

// Evidence of progress sampled from the pipeline.
struct ProgressSnapshot {
  std::uint64_t frames_completed = 0;  // left the processing stages (published or failed)
  std::size_t frames_pending = 0;      // queued or in a stage now
  std::chrono::steady_clock::time_point source_heartbeat{};  // last source-loop iteration
};

// Decides whether a WATCHDOG=1 is deserved (see the file comment).
class WatchdogGate {
 public:
  using Clock = std::chrono::steady_clock;
  explicit WatchdogGate(Clock::duration stall_limit) : stall_limit_(stall_limit) {}

  bool healthy(const ProgressSnapshot& progress, Clock::time_point now);
  // Why the last call said no (for the log), empty when healthy.
  const std::string& reason() const { return reason_; }

 private:
  Clock::duration stall_limit_;
  std::optional<std::uint64_t> last_completed_;
  Clock::time_point last_progress_{};
  std::string reason_;
};

// spdlog default logger: the systemd journal when stderr is connected to it
// ($JOURNAL_STREAM matches stderr's device:inode, as systemd documents),
// else a coloured console on stderr. `level` is one of trace debug info warn error.
void setupLogging(const std::string& level);
bool stderrIsJournal();

}  // namespace findmug::daemon
