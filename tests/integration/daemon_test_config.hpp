// findmugd's settings as a daemon test writes them (the tests that link the daemon).
#pragma once

#include <string>

#include "findmug/daemon/daemon_config.hpp"
#include "findmug/settings/config.hpp"

namespace findmug::daemon::test {

// set(KEY, VALUE) hands one `section.name` to findmugd's schema (daemonSchema), which
// parses it into the segmenter's sections (the Config base) or `daemon`, as from a file.
struct TestConfig : Config {
  DaemonConfig daemon;
  TestConfig& set(const std::string& key, const std::string& value) {
    daemonSchema(*this, daemon).set(key, value);
    return *this;
  }
};

}  // namespace findmug::daemon::test
