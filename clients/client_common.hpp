// client_common.hpp — small helpers shared by the findmug command-line clients:
// clean shutdown on SIGINT/SIGTERM and a bus receive loop (flags: cli/findmug_cli.hpp).
//
// The clients are single-threaded: the main thread owns the bus (io::LcmBus)
// and the subscribers' callbacks run inside Bus::handle() on it. A signal only
// sets a flag (cli::StopSignals) that the loop checks between waits, so no
// state is touched from a signal handler.
#pragma once

#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "findmug/io/bus.hpp"
#include "findmug/io/udpm.hpp"
#include "findmug_signals.hpp"

namespace findmug::clients {

// The client's one StopSignals, made by installStopHandlers() (before the loop).
inline cli::StopSignals& stopSignals() {
  static cli::StopSignals signals;
  return signals;
}
inline void installStopHandlers() { stopSignals(); }

// The client's bus on `url` (--lcm-url; empty = LCM's default provider) with its
// --channel-suffix applied by the bus (channels are then named by their base names), or
// null after saying on stderr that it cannot be opened.
inline std::shared_ptr<io::Bus> openBus(const std::string& url, const char* program,
                                        const std::string& channel_suffix) {
  try {
    return io::openBus(url, "--lcm-url", channel_suffix);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: cannot open LCM provider '%s': %s\n", program,
                 url.empty() ? "default" : url.c_str(), e.what());
    return nullptr;
  }
}

// Waits for messages until a stop signal, `done()` turns true, or the LCM
// source ends (a replayed log file reaches its end). Returns the exit code:
// 0 on a clean stop or end of a log, 1 when the LCM provider failed.
inline int receiveLoop(io::Bus& bus, const char* program, const std::function<bool()>& done) {
  while (!stopSignals().requested() && !done()) {
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
