// Fuzz target config_set: --set key=value lines (findmugd/tools flags) -> findmugd's settings schema.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/settings/config.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    // One --set key=value per line, applied in order to the defaults.
    findmug::daemon::LoadedConfig loaded;
    const findmug::SettingsSchema schema =
        findmug::daemon::daemonSchema(loaded.config, loaded.daemon);
    std::istringstream lines(std::string(reinterpret_cast<const char*>(data), size));
    std::string line;
    while (std::getline(lines, line)) schema.applyOverride(line);
    schema.validate("<flags>");
    (void)findmug::daemon::dumpDaemonConfig(loaded);
  } catch (const findmug::Error&) {
    // The expected answer to a bad input.
  }
  return 0;
}
