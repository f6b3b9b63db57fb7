// client_common.hpp — small helpers shared by the findmug command-line clients:
// clean shutdown on SIGINT/SIGTERM and an LCM receive loop (flags: cli/findmug_cli.hpp).
//
// The clients are single-threaded: LCM handlers run inside handleTimeout()
// on the main thread, and a signal only sets a flag (cli::StopSignals) that
// the loop checks between waits, so no state is touched from a signal handler.
#pragma once

#include <cstdio>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "findmug_signals.hpp"

namespace findmug::clients {

// The client's one StopSignals, made by installStopHandlers() (before the loop).
inline cli::StopSignals& stopSignals() {
  static cli::StopSignals signals;
  return signals;
}
inline void installStopHandlers() { stopSignals(); }

// Waits for messages until a stop signal, `done()` turns true, or the LCM
// source ends (a replayed log file reaches its end). Returns the exit code:
// 0 on a clean stop or end of a log, 1 when the LCM provider failed.
inline int receiveLoop(lcm::LCM& lcm, const std::string& url, const char* program,
                       const std::function<bool()>& done) {
  const bool from_log = url.rfind("file://", 0) == 0;
  while (!stopSignals().requested() && !done()) {
    const int status = lcm.handleTimeout(200);
    if (status < 0) {
      if (from_log) return 0;  // the log has been read to its end
      std::fprintf(stderr, "%s: LCM receive failed (provider %s)\n", program,
                   url.empty() ? "default" : url.c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace findmug::clients
