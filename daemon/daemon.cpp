// findmugd's run loop: source thread, pipeline, systemd notifications, shutdown.
#include "findmug/daemon/daemon.hpp"

#include <malloc.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>

#include "findmug/common/error.hpp"
#include "findmug/daemon/status_builder.hpp"
#include "findmug/io/frame_source.hpp"

namespace findmug::daemon {

namespace {
using Clock = std::chrono::steady_clock;

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// The settings the model gives that the config left at other values (configForModel), so
// that the start-up log's effective config is complete; refuses a conflicting given one.
void logSettingsTakenFromModel(const SegmenterConfig& config, const RandomForest& model) {
  const auto before = segmenterSettings().values(config);
  std::string taken;
  for (const auto& [key, value] : segmenterSettings().values(configForModel(config, model))) {
    if (before.at(key) != value) taken += " " + key + "=" + value;
  }
  if (!taken.empty()) spdlog::info("settings taken from the model:{}", taken);
}

}  // namespace

std::shared_ptr<const RandomForest> loadModel(const std::string& path, std::string* model_id) {
  try {
    auto forest = std::make_shared<const RandomForest>(RandomForest::load(path));
    if (forest->empty()) throw Error(path + ": model has no trees");
    if (model_id) *model_id = std::filesystem::path(path).filename().string() + ":" + forest->id();
    return forest;
  } catch (const Error& e) {
    throw Error(std::string("daemon.model_path: ") + e.what());
  }
}

Daemon::Daemon(const Config& config, const DaemonConfig& daemon_config, PipelineHooks hooks)
    : Daemon(config, daemon_config, std::unique_ptr<io::FrameSource>(), std::move(hooks)) {}

Daemon::Daemon(const Config& config, const DaemonConfig& daemon_config,
               std::unique_ptr<io::FrameSource> source, PipelineHooks hooks)
    : daemon_config_(daemon_config), source_(std::move(source)) {
  if (daemon_config_.heap_keep_mb > 0) {
    // A 640x480 frame allocates about 35 MB in buffers of a few MB, freed
    // when it is published. With glibc's default thresholds each comes fresh
    // from the kernel (page faults and zeroing, about a tenth of a frame's
    // CPU time: perf-log §9e); these keep them in the heap.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, daemon_config_.heap_keep_mb << 20);
  }
  std::string model_id;
  auto forest = loadModel(daemon_config_.model_path, &model_id);
  spdlog::info("model {} loaded from {} ({})", model_id, daemon_config_.model_path,
               forest->summary());
  logSettingsTakenFromModel(config.segmenter, *forest);
  double rate_hz = 0.0;
  if (!source_) {
    try {
      io::SourceSpec spec = io::parseSourceSpec(daemon_config_.source);
      // An lcm source without its own url listens where we publish.
      if (spec.kind == "lcm" && spec.options.lcm_url.empty()) {
        spec.options.lcm_url = effectiveLcmUrl(daemon_config_);
      }
      rate_hz = spec.options.rate_hz;
      source_ = io::makeSource(spec);
    } catch (const Error& e) {
      throw Error(std::string("daemon.source: ") + e.what());
    }
  }
  // A budget below two cores: every stage on the source thread, one frame
  // after another (the source's queue is then the door where frames wait).
  const ExecutionMode mode =
      daemon_config_.singleThreaded() ? ExecutionMode::Sequential : ExecutionMode::Threaded;
  // A paced file source legitimately waits one period inside next().
  const double timeout_s =
      std::max(daemon_config_.source_timeout_s, rate_hz > 0.0 ? 3.0 / rate_hz : 0.0);
  source_timeout_ = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(timeout_s));
  pipeline_ = std::make_unique<Pipeline>(config.segmenter, daemon_config_, std::move(forest),
                                         model_id, mode, std::move(hooks));
  pipeline_->attachSource(source_.get());
  if (mode == ExecutionMode::Sequential) {
    spdlog::info("source {}; daemon.max_cpu_cores {}: every stage on one thread",
                 source_->describe(), daemon_config_.max_cpu_cores);
  } else {
    spdlog::info("source {}; {} segmentation worker(s), queue capacity {}, max_cpu_cores {}",
                 source_->describe(), pipeline_->workers(), daemon_config_.queue_capacity,
                 daemon_config_.max_cpu_cores);
  }
}

Daemon::~Daemon() {
  if (source_) source_->stop();
  if (source_thread_.joinable()) source_thread_.join();
  if (pipeline_) pipeline_->stop(StopMode::Discard);
}

void Daemon::sourceLoop() {
  for (;;) {
    // Drop at the door: take the next frame only once the pipeline can
    // accept it; meanwhile frames wait in the source, which keeps the newest
    // and drops older ones before decoding them.
    while (!pipeline_->waitForRoom(std::chrono::milliseconds(100))) {
      // Alive, waiting on the pipeline (whose own progress the watchdog checks).
      source_last_return_ns_.store(nowNs());
      const io::SourceState state = source_->state();
      if (stop_requested_.load() || state == io::SourceState::Stopped ||
          state == io::SourceState::Failed) {
        break;
      }
    }
    source_call_ns_.store(nowNs());
    source_in_next_.store(true);
    std::optional<RgbdFrame> frame = source_->next();
    source_in_next_.store(false);
    source_last_return_ns_.store(nowNs());
    if (!frame) break;
    pipeline_->submit(std::move(*frame));
  }
  source_finished_.store(true);
}

ProgressSnapshot Daemon::progress() const {
  ProgressSnapshot p = pipeline_->progress();
  // A source blocked in next() in a live state (waiting for a frame,
  // reconnecting with back-off) is legitimately idle: count it as alive.
  // FrameSource::next() has no timeout, so a driver call hanging inside a
  // "running" source cannot be told apart from a quiet one; see service.hpp.
  const io::SourceState state = source_->state();
  // ... unless it has reported "running" for longer than the source timeout
  // without returning: a driver call that hangs (sourceHung).
  const bool live_wait = (source_in_next_.load() && state != io::SourceState::Failed &&
                          state != io::SourceState::Stopped && !sourceHung(Clock::now())) ||
                         (source_finished_.load() && state == io::SourceState::EndOfStream);
  p.source_heartbeat =
      live_wait ? Clock::now()
                : Clock::time_point(std::chrono::nanoseconds(source_last_return_ns_.load()));
  return p;
}

bool Daemon::sourceHung(Clock::time_point now) const {
  if (!source_in_next_.load() || source_->state() != io::SourceState::Running) return false;
  const auto entered = Clock::time_point(std::chrono::nanoseconds(source_call_ns_.load()));
  return now - entered > source_timeout_;
}

int Daemon::run() {
  pipeline_->start();
  source_last_return_ns_.store(nowNs());
  source_thread_ = std::thread([this] { sourceLoop(); });
  notifier_.ready("model " + pipeline_->modelId() + ", source " + source_->describe());
  spdlog::info("findmugd ready");

  std::optional<WatchdogGate> gate;
  Clock::duration ping_period{};
  if (const auto timeout = notifier_.watchdogTimeout()) {
    gate.emplace(*timeout / 2);
    ping_period = *timeout / 3;
    spdlog::info("systemd watchdog: {} ms, pinged every {} ms while frames progress",
                 std::chrono::duration_cast<std::chrono::milliseconds>(*timeout).count(),
                 std::chrono::duration_cast<std::chrono::milliseconds>(ping_period).count());
  }
  auto next_ping = Clock::now();
  auto next_status_text = Clock::now() + std::chrono::seconds(5);
  auto next_heap_trim = Clock::now() + std::chrono::seconds(5);
  bool warned_unhealthy = false;
  bool reported_hung = false;

  // With exit_at_end_of_stream off, an exhausted source leaves the daemon up
  // and idle (status still published) until it is asked to stop.
  auto source_done = [&] {
    return source_finished_.load() && (daemon_config_.exit_at_end_of_stream ||
                                       source_->state() != io::SourceState::EndOfStream);
  };
  while (!stop_requested_.load() && !source_done()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    // Sequential mode: status also while no frame comes (no-op when threaded).
    pipeline_->publishStatusIfDue();
    const auto now = Clock::now();
    const bool hung = sourceHung(now);
    if (hung && !reported_hung) {
      spdlog::error(
          "source {} is hung: no frame, no error and no state change for {:.1f} s while "
          "'running' (daemon.source_timeout_s); the watchdog is no longer fed",
          source_->describe(), std::chrono::duration<double>(source_timeout_).count());
      notifier_.status("source hung: no frame for " +
                       fmt::format("{:.1f}", std::chrono::duration<double>(source_timeout_).count()) +
                       " s while running");
    } else if (!hung && reported_hung) {
      spdlog::info("source {} delivers again", source_->describe());
    }
    reported_hung = hung;
    if (gate && now >= next_ping) {
      if (gate->healthy(progress(), now)) {
        notifier_.watchdog();
        warned_unhealthy = false;
      } else if (!warned_unhealthy) {
        spdlog::error("withholding watchdog ping: {}", gate->reason());
        warned_unhealthy = true;
      }
      next_ping = now + ping_period;
    }
    // Each frame's large buffers are allocated and freed on several threads,
    // each with its own glibc arena; freed pages stay mapped, and over hours
    // RSS climbs with the load although nothing leaks. Hand them back to the
    // kernel every few seconds (a few ms of one core), so RSS means what is used.
    if (now >= next_heap_trim) {
      malloc_trim(0);
      next_heap_trim = now + std::chrono::seconds(5);
    }
    if (now >= next_status_text && !hung) {
      // The same figures as status_t, for `systemctl status` and the journal.
      const findmug_lcm::status_t s = makeStatus(*pipeline_);
      const auto total =
          std::find(s.stage_names.begin(), s.stage_names.end(), "total") - s.stage_names.begin();
      const std::string line = fmt::format(
          "{} received, {} processed, {} dropped, {} rejected; in {:.2f} fps, out {:.2f} fps; "
          "latency p50 {:.0f} ms, p95 {:.0f} ms; CPU {:.2f} cores (budget {}); source {}",
          s.frames_received, s.frames_processed, s.frames_dropped, s.frames_rejected, s.input_fps,
          s.output_fps, s.latency_p50_us[total] / 1000.0, s.latency_p95_us[total] / 1000.0,
          s.cpu_used_cores, s.cpu_budget_cores > 0 ? fmt::format("{:g}", s.cpu_budget_cores)
                                                   : std::string("none"),
          s.source_state_name);
      notifier_.status(line);
      spdlog::info("{}", line);
      next_status_text = now + std::chrono::seconds(10);
    }
  }

  const io::SourceState final_state = source_->state();
  const bool stop_request = stop_requested_.load();
  notifier_.stopping(stop_request ? "stopping on request" : "source ended");
  spdlog::info("shutting down ({})",
               stop_request
                   ? "stop requested"
                   : std::string("source ") + std::string(io::sourceStateName(final_state)));
  // An exhausted source keeps its EndOfStream state for the final status.
  if (!(source_finished_.load() && final_state == io::SourceState::EndOfStream)) source_->stop();
  if (source_thread_.joinable()) source_thread_.join();
  // On request: latency matters (systemd waits), drop what is queued. At the
  // end of a finite stream every frame is still wanted.
  pipeline_->stop(stop_request ? StopMode::Discard : StopMode::Drain);
  const std::string last_source_error = source_->stats().last_error;  // before closing it
  // Close the device / files / input LCM handle now, not whenever the
  // Daemon is destroyed.
  pipeline_->attachSource(nullptr);
  source_.reset();

  if (!stop_request && final_state == io::SourceState::Failed) {
    spdlog::error("source failed: {}", last_source_error);
    return 1;
  }
  return 0;
}

}  // namespace findmug::daemon
