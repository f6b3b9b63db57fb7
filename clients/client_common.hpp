// client_common.hpp — small helpers shared by the findmug command-line clients:
// clean shutdown on SIGINT/SIGTERM and an LCM receive loop (flags: tools/cli/findmug_cli.hpp).
//
// The clients are single-threaded: LCM handlers run inside handleTimeout()
// on the main thread, and a signal only sets a flag that the loop checks
// between waits, so no state is touched from a signal handler.
#pragma once

#include <csignal>
#include <cstdio>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

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
inline int receiveLoop(lcm::LCM& lcm, const std::string& url, const char* program,
                       const std::function<bool()>& done) {
  const bool from_log = url.rfind("file://", 0) == 0;
  while (!g_stop_requested && !done()) {
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
