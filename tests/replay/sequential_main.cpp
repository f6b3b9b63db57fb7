// findmug-sequential — findmugd's work done by one thread, frame after frame.
//
//   findmug-sequential [findmugd's flags: --config, --set, --source, --lcm-url, --model, ...]
//
// The benchmark's baseline for "what does pipelining buy": the same library,
// the same Pipeline class, the same frame source, config and LCM output as
// findmugd, but in ExecutionMode::Sequential — every stage of a frame runs on
// the main thread, and the next frame is taken from the source only when the
// previous one is published. Frames that arrive meanwhile wait in the
// source's small queue (daemon.source ...?queue=N, default 2), oldest dropped
// and counted, as in the daemon.
//
// Stops on SIGTERM/SIGINT or at the end of a finite source, then publishes a
// final status (source_state STOPPED / END_OF_STREAM) like findmugd.
#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>
#include <thread>

#include "findmug/daemon/daemon.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/daemon/service.hpp"
#include "findmug/error.hpp"
#include "findmug/io/frame_source.hpp"

int main(int argc, char** argv) {
  using namespace findmug;
  using namespace findmug::daemon;

  // Signals are taken by one thread (sigwait), as in findmugd.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  LoadedConfig loaded;
  try {
    const CommandLine command_line =
        parseCommandLine(std::vector<std::string>(argv + 1, argv + argc));
    if (command_line.help) {
      std::cout << "findmug-sequential: findmugd's pipeline on one thread (benchmark baseline)\n"
                << usage();
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

    std::thread signal_thread([&source, &signals] {
      int signal_number = 0;
      while (sigwait(&signals, &signal_number) == 0) {
        if (signal_number == SIGTERM || signal_number == SIGINT) {
          source->stop();
          return;
        }
      }
    });
    while (std::optional<RgbdFrame> frame = source->next()) {
      pipeline.submit(std::move(*frame));
    }
    const io::SourceState state = source->state();
    source->stop();
    pipeline.stop(StopMode::Discard);
    // Wake the signal thread if the source ended on its own.
    pthread_kill(signal_thread.native_handle(), SIGTERM);
    signal_thread.join();
    return state == io::SourceState::Failed ? 1 : 0;
  } catch (const std::exception& e) {
    spdlog::critical("findmug-sequential: {}", e.what());
    return 2;
  }
}
