// findmug/daemon/daemon_config.hpp — findmugd's own settings and command line.
//
// findmugd reads the segmenter's sections into a Config and its own `daemon:`,
// `check:`, `table_map:` and `semantic_map:` sections into a DaemonConfig (the
// structs and tables: cli/program_settings.hpp, shared with the programs that
// read the same file); each value is parsed once into its field while the file
// is read (findmug::SettingsSchema). An unknown section or key, or a bad value,
// is a findmug::Error naming it, and start-up stops. daemon/findmugd.yaml is
// the annotated default file.
//
// Precedence, lowest first: built-in defaults < YAML file < command-line
// flags. daemon.lcm_url left empty means $LCM_DEFAULT_URL, then liblcm's
// own default.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"
#include "program_settings.hpp"

namespace findmug::daemon {

// Compiled-in default locations (CMake passes the install prefix).
std::string defaultConfigPath();  // /etc/findmug/findmugd.yaml

// The resolved output LCM URL ($LCM_DEFAULT_URL when daemon.lcm_url is empty).
std::string effectiveLcmUrl(const DaemonConfig& config);

// Where robot poses are read from, or nullopt when there is no pose input:
// daemon.pose_input off, or daemon.pose_url empty while the output goes to a
// file:// log (a log being written has no poses to read). Empty pose_url
// otherwise means the output provider (effectiveLcmUrl), where the robot's
// localisation publishes on the same LCM network.
std::optional<std::string> effectivePoseUrl(const DaemonConfig& config);

// Where commands are read from, or nullopt when there is no command input: the
// same rule as effectivePoseUrl with daemon.command_input and daemon.command_url.
std::optional<std::string> effectiveCommandUrl(const DaemonConfig& config);

// Parsed command line of findmugd.
struct CommandLine {
  std::optional<std::string> config_path;  // --config; default file used when absent
  std::vector<std::string> overrides;      // key=value, in order
  bool check_config = false;               // --check-config: validate, print, exit
  bool check = false;                      // --check: first-run self-test (check.hpp), exit
  bool help_settings = false;              // --help-settings: list every setting, exit
  bool help = false;
  bool version = false;  // --version: print "findmugd VERSION", exit
};

// Throws findmug::Error for unknown flags or missing values.
CommandLine parseCommandLine(const std::vector<std::string>& args);
std::string usage();
// The flags that stand for one daemon setting ("--model" -> "daemon.model_path").
const std::vector<std::pair<std::string, std::string>>& daemonFlagShortcuts();

// findmugd's settings schema: daemonSchema (program_settings.hpp).

// Reads the file (the default one may be absent: then built-in defaults) and the
// overrides through daemonSchema, then checks the rules across keys.
struct LoadedConfig {
  Config config;
  DaemonConfig daemon;
  std::string origin;  // which file was read, or "built-in defaults"
};
LoadedConfig loadDaemonConfig(const CommandLine& command_line);
// The same from YAML text (tests, the config fuzzer); `origin` names it in errors.
LoadedConfig parseDaemonConfig(const std::string& yaml_text, const std::string& origin);
// Every setting of the file findmugd reads, with its built-in default, what a value
// must be and its doc line (--help-settings; SettingsSchema::help).
std::string settingsHelp();
// The effective values of every section findmugd reads, as YAML (--check-config).
std::string dumpDaemonConfig(const LoadedConfig& loaded);

}  // namespace findmug::daemon
