// findmugd — real-time semantic segmentation daemon (see daemon/include/findmug/daemon/daemon.hpp).
//
// Thin: parse flags, load and log the config, set up logging, turn SIGTERM /
// SIGINT into Daemon::requestStop(), run. Signals are blocked in every thread
// and taken synchronously by one dedicated thread (cli::StopSignals), so no
// library call on a worker thread is interrupted by EINTR.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/daemon/check.hpp"
#include "findmug/daemon/daemon.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/service.hpp"
#include "findmug/version.hpp"
#include "findmug_signals.hpp"

int main(int argc, char** argv) {
  using namespace findmug;
  using namespace findmug::daemon;

  // Before any thread: the mask is inherited by every thread. SIGHUP reloads the model.
  cli::StopSignals stop_signals(/*take_hangup=*/true);

  LoadedConfig loaded;
  CommandLine command_line;
  try {
    command_line = parseCommandLine(std::vector<std::string>(argv + 1, argv + argc));
    if (command_line.help) {
      std::cout << usage();
      return 0;
    }
    if (command_line.help_settings) {
      std::cout << settingsHelp();
      return 0;
    }
    if (command_line.version) {
      std::cout << "findmugd " << kVersion << "\n";
      return 0;
    }
    loaded = loadDaemonConfig(command_line);
    setupLogging(loaded.daemon.log_level);
    if (command_line.check_config) {
      std::cout << dumpDaemonConfig(loaded);
      return 0;
    }
  } catch (const std::exception& e) {
    if (command_line.check) {
      std::cout << verdictLine(Verdict::Fail, "config", e.what(),
                               "correct the named setting (findmugd --check-config prints the "
                               "effective config)")
                << "findmugd --check: 1 item failed\n";
      return 1;
    }
    std::fprintf(stderr, "findmugd: configuration error: %s\n", e.what());
    return 2;
  }
  if (command_line.check) {
    // Library logging (source reconnects etc.) would interleave with the verdicts.
    spdlog::set_level(spdlog::level::off);
    const int failures = runSelfCheck(loaded, std::cout);
    std::cout << "findmugd --check: "
              << (failures == 0 ? std::string("all items passed")
                                : std::to_string(failures) + " item(s) failed")
              << "\n";
    return failures == 0 ? 0 : 1;
  }

  spdlog::info("findmugd starting; config from {}; effective config:\n{}", loaded.origin,
               dumpDaemonConfig(loaded));
  try {
    Daemon daemon(loaded.config, loaded.daemon);
    const auto stop_registration = stop_signals.onStop([&daemon] { daemon.requestStop(); });
    stop_signals.onHangup([&daemon] { daemon.requestModelReload(-1, "SIGHUP"); });
    // Cleared before the daemon goes, however run() ends.
    struct ClearHangup {
      cli::StopSignals& signals;
      ~ClearHangup() { signals.onHangup({}); }
    } clear_hangup{stop_signals};
    const int code = daemon.run();
    spdlog::info("findmugd exiting with code {}", code);
    // Everything observable is done: final status published, LCM handles and
    // the source closed. A segmentation still running past the shutdown
    // grace period cannot be interrupted and its result is not wanted, so
    // leave without joining it (~Daemon would), to stay within systemd's
    // and the robot's patience.
    spdlog::shutdown();
    std::fflush(nullptr);
    std::_Exit(code);
  } catch (const std::exception& e) {
    spdlog::critical("findmugd: {}", e.what());
    return 2;
  }
}
