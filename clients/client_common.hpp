// client_common.hpp — small helpers shared by the findmug command-line clients:
// clean shutdown on SIGINT/SIGTERM and a bus receive loop (flags: tools/cli/findmug_cli.hpp).
//
// The clients are single-threaded: the main thread owns the bus (io::LcmBus)
// and the subscribers' callbacks run inside Bus::handle() on it. A signal only
// sets a flag that the loop checks between waits, so no state is touched from
// a signal handler.
#pragma once

#include <chrono>
#include <csignal>
#include <cstdio>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "findmug/io/bus.hpp"

namespace findmug::clients {

inline volatile std::sig_atomic_t g_stop_requested = 0;

inline void installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = [](int) { g_stop_requested = 1; };
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

// Waits for messages until a stop signal, `done()` turns true, or the LCM
// source ends (a replayed log file reaches its end). Returns the exit code:
// 0 on a clean stop or end of a log, 1 when the LCM provider failed.
inline int receiveLoop(io::Bus& bus, const char* program, const std::function<bool()>& done) {
  while (!g_stop_requested && !done()) {
    const io::HandleResult result = bus.handle(std::chrono::milliseconds(200));
    if (result == io::HandleResult::EndOfLog) return 0;  // the log has been read to its end
    if (result == io::HandleResult::Failed) {
      std::fprintf(stderr, "%s: LCM receive failed (provider %s)\n", program,
                   bus.describe().c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace findmug::clients
