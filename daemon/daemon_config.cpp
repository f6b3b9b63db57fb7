// findmugd settings: which tables it reads, its command line, the effective URLs.
#include "findmug/daemon/daemon_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug_cli.hpp"
#include "program_settings.hpp"

#ifndef FINDMUG_SYSCONF_DIR
#define FINDMUG_SYSCONF_DIR "/etc"
#endif

namespace findmug::daemon {

std::string defaultConfigPath() { return FINDMUG_SYSCONF_DIR "/findmug/findmugd.yaml"; }

int DaemonConfig::effectiveWorkers() const {
  int n = workers;
  if (n <= 0) {
    const unsigned cores = std::thread::hardware_concurrency();
    n = cores == 0 ? 1 : static_cast<int>(cores);
  }
  // A budget of k cores leaves k - 1 for segmentation: the prepare stage
  // keeps one busy too (publishing is light).
  if (max_cpu_cores >= 2.0) n = std::min(n, static_cast<int>(std::floor(max_cpu_cores)) - 1);
  if (singleThreaded()) n = 1;
  return std::max(n, 1);
}

std::string effectiveLcmUrl(const DaemonConfig& config) {
  if (!config.lcm_url.empty()) return config.lcm_url;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) return env;
  return "";  // liblcm's built-in default
}

std::optional<std::string> effectivePoseUrl(const DaemonConfig& config) {
  if (!config.pose_input) return std::nullopt;
  if (!config.pose_url.empty()) return config.pose_url;
  const std::string output = effectiveLcmUrl(config);
  if (output.rfind("file://", 0) == 0) return std::nullopt;
  return output;
}

std::optional<std::string> effectiveCommandUrl(const DaemonConfig& config) {
  if (!config.command_input) return std::nullopt;
  if (!config.command_url.empty()) return config.command_url;
  const std::string output = effectiveLcmUrl(config);
  if (output.rfind("file://", 0) == 0) return std::nullopt;
  return output;
}

namespace {

// findmugd's flags on the shared CLI layer. Values land in `cl` only through
// parse_order() (below), which keeps --set and its shortcuts in command-line order.
std::unique_ptr<CLI::App> daemonApp(CommandLine& cl) {
  auto app = cli::makeApp("findmugd", "findmug real-time semantic segmentation daemon");
  app->add_option("--config")
      ->description("YAML config (default " + defaultConfigPath() + ")")
      ->type_name("PATH");
  app->add_option("--set")
      ->description("override any setting, e.g. --set mrf.lambda=2 (repeatable)")
      ->type_name("KEY=VALUE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  for (const auto& [flag, key] : daemonFlagShortcuts()) {
    app->add_option(flag)
        ->description("same as --set " + key + "=VALUE")
        ->type_name("VALUE")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  }
  app->add_flag("--check-config", cl.check_config,
                "validate and print the effective config, then exit");
  app->add_flag("--help-settings", cl.help_settings,
                "list every setting: key = built-in default (what a value must be), its doc "
                "line; [model] marks the keys a model records and sets unless given");
  app->add_flag("--check", cl.check,
                "first-run self-test: config, model, source, frames, ground plane, one "
                "labelled frame; one verdict line each; exit 0 when nothing failed");
  app->footer(
      "Environment: LCM_DEFAULT_URL (used when daemon.lcm_url is empty), NOTIFY_SOCKET,\n"
      "WATCHDOG_USEC (systemd), JOURNAL_STREAM (log to the journal).");
  return app;
}

}  // namespace

const std::vector<std::pair<std::string, std::string>>& daemonFlagShortcuts() {
  static const std::vector<std::pair<std::string, std::string>> shortcuts = {
      {"--source", "daemon.source"},
      {"--lcm-url", "daemon.lcm_url"},
      {"--channel-suffix", "daemon.channel_suffix"},
      {"--model", "daemon.model_path"},
      {"--workers", "daemon.workers"},
      {"--log-level", "daemon.log_level"}};
  return shortcuts;
}

std::string usage() {
  CommandLine unused;
  return daemonApp(unused)->help();
}

CommandLine parseCommandLine(const std::vector<std::string>& args) {
  CommandLine cl;
  auto app = daemonApp(cl);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 pops from the back
  try {
    app->parse(reversed);
  } catch (const CLI::CallForHelp&) {
    cl.help = true;
    return cl;
  } catch (const CLI::CallForVersion&) {
    cl.version = true;
    return cl;
  } catch (const CLI::ParseError& e) {
    throw Error(std::string(e.what()) + " (see --help)");
  }
  // Every occurrence of a value flag, in command-line order.
  std::map<const CLI::Option*, std::size_t> seen;
  for (const CLI::Option* option : app->parse_order()) {
    const std::string name = "--" + option->get_single_name();
    const std::size_t k = seen[option]++;
    if (name == "--check-config" || name == "--check" || name == "--help-settings") continue;
    const std::string& value = option->results().at(k);
    if (name == "--config") {
      cl.config_path = value;
    } else if (name == "--set") {
      cl.overrides.push_back(value);
    } else {
      for (const auto& [flag, key] : daemonFlagShortcuts()) {
        if (flag == name) cl.overrides.push_back(key + "=" + value);
      }
    }
  }
  return cl;
}

LoadedConfig loadDaemonConfig(const CommandLine& command_line) {
  LoadedConfig loaded;
  const SettingsSchema schema = daemonSchema(loaded.config, loaded.daemon);
  if (command_line.config_path) {
    loaded.origin = *command_line.config_path;
    schema.readFile(loaded.origin);
  } else if (std::filesystem::exists(defaultConfigPath())) {
    loaded.origin = defaultConfigPath();
    schema.readFile(loaded.origin);
  } else {
    loaded.origin = "built-in defaults (no " + defaultConfigPath() + ")";
  }
  for (const auto& o : command_line.overrides) schema.applyOverride(o);
  schema.validate(command_line.overrides.empty() ? loaded.origin : loaded.origin + " + flags");
  return loaded;
}

LoadedConfig parseDaemonConfig(const std::string& yaml_text, const std::string& origin) {
  LoadedConfig loaded;
  loaded.origin = origin;
  const SettingsSchema schema = daemonSchema(loaded.config, loaded.daemon);
  schema.readYaml(yaml_text, origin);
  schema.validate(origin);
  return loaded;
}

std::string settingsHelp() {
  Config config;
  DaemonConfig daemon;
  return daemonSchema(config, daemon).help();
}

std::string dumpDaemonConfig(const LoadedConfig& loaded) {
  LoadedConfig copy = loaded;  // the schema binds to non-const structs; dump only reads
  return daemonSchema(copy.config, copy.daemon).dump();
}

}  // namespace findmug::daemon
