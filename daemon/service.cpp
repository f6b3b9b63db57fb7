// systemd integration: sd_notify, the progress-gated watchdog, journal logging.
#include "findmug/daemon/service.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/systemd_sink.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <memory>

namespace findmug::daemon {

SystemdNotifier::SystemdNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  enabled_ = socket && *socket;
  std::uint64_t usec = 0;
  // 0 unset_environment: children (none) and later re-reads see the same values.
  if (sd_watchdog_enabled(0, &usec) > 0 && usec > 0) {
    watchdog_ = std::chrono::microseconds(usec);
  }
}

void SystemdNotifier::send(const std::string& message) const {
  if (!enabled_) return;
  const int r = sd_notify(0, message.c_str());
  if (r < 0) spdlog::warn("sd_notify failed: {}", std::strerror(-r));
}

void SystemdNotifier::ready(const std::string& status) const { send("READY=1\nSTATUS=" + status); }
void SystemdNotifier::watchdog() const { send("WATCHDOG=1"); }
void SystemdNotifier::stopping(const std::string& status) const {
  send("STOPPING=1\nSTATUS=" + status);
}
void SystemdNotifier::status(const std::string& status) const { send("STATUS=" + status); }

bool WatchdogGate::healthy(const ProgressSnapshot& progress, Clock::time_point now) {
  if (!last_completed_ || progress.frames_completed != *last_completed_) {
    last_completed_ = progress.frames_completed;
    last_progress_ = now;
  }
  if (now - progress.source_heartbeat > stall_limit_) {
    reason_ = "source thread has not come round its loop for " +
              std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(
                                 now - progress.source_heartbeat)
                                 .count()) +
              " ms";
    return false;
  }
  if (progress.frames_pending > 0 && now - last_progress_ > stall_limit_) {
    reason_ =
        std::to_string(progress.frames_pending) + " frame(s) pending but none completed for " +
        std::to_string(
            std::chrono::duration_cast<std::chrono::milliseconds>(now - last_progress_).count()) +
        " ms";
    return false;
  }
  reason_.clear();
  return true;
}

bool stderrIsJournal() {
  const char* stream = std::getenv("JOURNAL_STREAM");
  if (!stream || !*stream) return false;
  unsigned long long dev = 0, ino = 0;
  if (std::sscanf(stream, "%llu:%llu", &dev, &ino) != 2) return false;
  struct stat st {};
  if (fstat(STDERR_FILENO, &st) != 0) return false;
  return static_cast<unsigned long long>(st.st_dev) == dev &&
         static_cast<unsigned long long>(st.st_ino) == ino;
}

void setupLogging(const std::string& level) {
  std::shared_ptr<spdlog::logger> logger;
  if (stderrIsJournal()) {
    // Structured journal entries with priorities; the journal adds its own time stamps.
    logger = std::make_shared<spdlog::logger>(
        "findmugd", std::make_shared<spdlog::sinks::systemd_sink_mt>("findmugd"));
  } else {
    logger = std::make_shared<spdlog::logger>(
        "findmugd", std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  }
  logger->set_level(spdlog::level::from_str(level));
  logger->flush_on(spdlog::level::warn);
  spdlog::set_default_logger(logger);
}

}  // namespace findmug::daemon
