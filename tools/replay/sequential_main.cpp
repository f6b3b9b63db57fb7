// findmug-sequential — findmugd's work done by one thread, frame after frame.
//
//   findmug-sequential [findmugd's flags: --config, --set, --source, --lcm-url, --model, ...]
//
// The benchmark's baseline for "what does pipelining buy": the same library,
// the same Pipeline class, the same frame source, config and LCM output as
// findmugd, but in ExecutionMode::Sequential — every stage of a frame runs on
// the main thread, and the next frame is processed only when the previous one
// is published. Frames that arrive meanwhile wait in the source's small queue
// (daemon.source ...?queue=N, default 2, oldest dropped and counted, as in the
// daemon) plus one held by the thread that reads the source.
//
// Stops on SIGTERM/SIGINT or at the end of a finite source, then publishes a
// final status (source_state STOPPED / END_OF_STREAM) like findmugd.
#include <spdlog/spdlog.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <optional>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/daemon/daemon.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/daemon/service.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/version.hpp"
#include "findmug_signals.hpp"

int main(int argc, char** argv) {
  using namespace findmug;
  using namespace findmug::daemon;

  // Signals are taken by one thread (sigwait), as in findmugd.
  cli::StopSignals stop_signals;

  LoadedConfig loaded;
  try {
    const CommandLine command_line =
        parseCommandLine(std::vector<std::string>(argv + 1, argv + argc));
    if (command_line.help) {
      std::cout << "findmug-sequential: findmugd's pipeline on one thread (benchmark baseline)\n"
                << usage();
      return 0;
    }
    if (command_line.version) {
      std::cout << "findmug-sequential " << kVersion << "\n";
      return 0;
    }
    loaded = loadDaemonConfig(command_line);
    setupLogging(loaded.daemon.log_level);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "findmug-sequential: configuration error: %s\n", e.what());
    return 2;
  }

  try {
    std::string model_id;
    auto forest = loadModel(loaded.daemon.model_path, &model_id);
    io::SourceSpec spec = io::parseSourceSpec(loaded.daemon.source);
    if (spec.kind == "lcm" && spec.options.lcm_url.empty()) {
      spec.options.lcm_url = effectiveLcmUrl(loaded.daemon);
    }
    auto source = io::makeSource(spec);
    Pipeline pipeline(loaded.config.segmenter, loaded.daemon, std::move(forest), model_id,
                      ExecutionMode::Sequential);
    pipeline.attachSource(source.get());
    pipeline.start();
    // Announce ourselves (findmugd's publish thread does this periodically;
    // here statuses otherwise go out only between frames).
    pipeline.publishStatusNow();
    spdlog::info("findmug-sequential: model {}, source {}", model_id, source->describe());

    const auto stop_registration = stop_signals.onStop([&source] { source->stop(); });

    // A reader thread takes frames from the source and hands them over one at
    // a time (it holds at most one while the main thread is busy; the source's
    // own queue buffers the rest, oldest dropped). The main thread alone
    // touches the pipeline: it processes a handed-over frame, or, when none
    // comes for a status period, publishes a status, so that watchers see the
    // counters settle after the input stops (findmugd's publish thread does
    // that on its own).
    std::mutex mutex;
    std::condition_variable changed;
    std::optional<RgbdFrame> handed;
    bool source_done = false;
    std::thread reader([&] {
      while (std::optional<RgbdFrame> frame = source->next()) {
        std::unique_lock lock(mutex);
        changed.wait(lock, [&] { return !handed; });
        handed = std::move(frame);
        changed.notify_all();
      }
      std::lock_guard lock(mutex);
      source_done = true;
      changed.notify_all();
    });
    const auto status_period = std::chrono::duration<double>(loaded.daemon.status_period_s);
    auto last_status = std::chrono::steady_clock::now();
    for (;;) {
      std::unique_lock lock(mutex);
      changed.wait_for(lock, status_period, [&] { return handed || source_done; });
      if (handed) {
        RgbdFrame frame = std::move(*handed);
        handed.reset();
        changed.notify_all();
        lock.unlock();
        pipeline.submit(std::move(frame));
      } else if (source_done) {
        break;
      } else {
        lock.unlock();
      }
      if (std::chrono::steady_clock::now() - last_status >= status_period) {
        pipeline.publishStatusNow();
        last_status = std::chrono::steady_clock::now();
      }
    }
    reader.join();
    const io::SourceState state = source->state();
    source->stop();
    pipeline.stop(StopMode::Discard);
    return state == io::SourceState::Failed ? 1 : 0;
  } catch (const std::exception& e) {
    spdlog::critical("findmug-sequential: {}", e.what());
    return 2;
  }
}
