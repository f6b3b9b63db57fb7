// Fuzz target config_yaml: YAML config text -> findmugd's settings schema (findmugd.yaml).
#include <cstddef>
#include <cstdint>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/settings/config.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const findmug::daemon::LoadedConfig loaded = findmug::daemon::parseDaemonConfig(
        std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml");
    (void)findmug::daemon::dumpDaemonConfig(loaded);
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
