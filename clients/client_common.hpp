// client_common.hpp — small helpers shared by the findmug command-line clients:
// flag parsing, clean shutdown on SIGINT/SIGTERM, and an LCM receive loop.
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

// "--name value" and "--flag" arguments. Unknown flags and missing values
// throw std::invalid_argument naming the flag.
class Flags {
 public:
  Flags(int argc, char** argv, const std::vector<std::string>& with_value,
        const std::vector<std::string>& switches) {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (contains(switches, arg)) {
        values_.insert_or_assign(arg, std::string());  // present, no value
      } else if (contains(with_value, arg)) {
        if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
        values_.insert_or_assign(arg, std::string(argv[++i]));
      } else {
        throw std::invalid_argument("unknown argument '" + arg + "' (see --help)");
      }
    }
  }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::string get(const std::string& name, const std::string& fallback) const {
    const auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }
  long getInt(const std::string& name, long fallback, long min_value) const {
    if (!has(name)) return fallback;
    const std::string text = get(name, "");
    std::size_t used = 0;
    long value = 0;
    try {
      value = std::stol(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || value < min_value) {
      throw std::invalid_argument(name + " " + text +
                                  ": expected an integer >= " + std::to_string(min_value));
    }
    return value;
  }
  double getDouble(const std::string& name, double fallback, double lo, double hi) const {
    if (!has(name)) return fallback;
    const std::string text = get(name, "");
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || !(value >= lo && value <= hi)) {
      throw std::invalid_argument(name + " " + text + ": expected a number in [" +
                                  std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return value;
  }

 private:
  static bool contains(const std::vector<std::string>& list, const std::string& s) {
    for (const auto& x : list) {
      if (x == s) return true;
    }
    return false;
  }
  std::map<std::string, std::string> values_;
};

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
