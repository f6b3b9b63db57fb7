// findmug/daemon/daemon.hpp — findmugd as an object: source thread, pipeline, watchdog, shutdown.
//
// Construction does everything that can fail for configuration reasons —
// load the model, open the frame source, open LCM — and throws
// findmug::Error naming the key, so start-up stops with a clear message.
// run() then:
//   1. starts the pipeline and the source thread (the only caller of
//      FrameSource::next(), which owns any input LCM handle inside the source);
//      the source thread takes a frame only when the pipeline has room for it
//      (Pipeline::waitForRoom), so overload drops frames in the source before
//      any work; with daemon.max_cpu_cores below 2 the pipeline is sequential
//      and the source thread runs every stage itself,
//   2. tells systemd READY=1,
//   3. loops every 50 ms: honours requestStop(), publishes the status of a
//      sequential pipeline when it is due, pings the watchdog when the
//      WatchdogGate sees progress, and notices the source ending,
//   4. reloads the model on requestModelReload() (SIGHUP, a reload_model command)
//      in the background, swapping it in between frames (model_reload.hpp),
//   5. shuts down: STOPPING=1, source->stop(), pipeline stop (queued frames
//      are dropped on a stop request, drained at end of stream), final status.
//
// Exit codes: 0 after a stop request or an exhausted finite source, 1 when
// the source failed for good (so Restart=on-failure brings the daemon back).
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/daemon/service.hpp"
#include "findmug/settings/config.hpp"

namespace findmug::io {
class FrameSource;
}

namespace findmug::daemon {

class Daemon {
 public:
  Daemon(const Config& config, const DaemonConfig& daemon_config, PipelineHooks hooks = {});
  // With a ready-made source instead of daemon.source (tests: a source that
  // fails or hangs on command).
  Daemon(const Config& config, const DaemonConfig& daemon_config,
         std::unique_ptr<io::FrameSource> source, PipelineHooks hooks = {});
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Blocks until requestStop() or the end of the source; returns the exit code.
  int run();
  // Thread-safe and async-signal-safe (one atomic store).
  void requestStop() { stop_requested_.store(true); }

  // Thread-safe, never blocks: see Pipeline::requestModelReload.
  void requestModelReload(std::int64_t request_id, const std::string& origin) {
    pipeline_->requestModelReload(request_id, origin);
  }

  const Pipeline& pipeline() const { return *pipeline_; }
  // Valid until run() returns (run closes the source on its way out).
  const io::FrameSource& source() const { return *source_; }

 private:
  void sourceLoop();
  ProgressSnapshot progress() const;
  // True when the source has been inside next() longer than the source
  // timeout while reporting Running (see DaemonConfig::source_timeout_s).
  bool sourceHung(std::chrono::steady_clock::time_point now) const;

  DaemonConfig daemon_config_;
  SystemdNotifier notifier_;
  std::unique_ptr<io::FrameSource> source_;
  std::unique_ptr<Pipeline> pipeline_;
  std::thread source_thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> source_finished_{false};
  std::atomic<bool> source_in_next_{false};
  std::atomic<std::int64_t> source_last_return_ns_{0};  // steady clock, ns
  std::atomic<std::int64_t> source_call_ns_{0};         // when next() was entered
  std::chrono::nanoseconds source_timeout_{};
};

// The model file as a forest plus "FILE:ID" for status messages; throws
// findmug::Error naming daemon.model_path when it cannot be loaded.
std::shared_ptr<const RandomForest> loadModel(const std::string& path, std::string* model_id);

}  // namespace findmug::daemon
