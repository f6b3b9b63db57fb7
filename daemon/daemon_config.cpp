// findmugd settings: the `daemon:` section of the YAML file and the command line.
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

#ifndef FINDMUG_SYSCONF_DIR
#define FINDMUG_SYSCONF_DIR "/etc"
#endif
#ifndef FINDMUG_DATA_INSTALL_DIR
#define FINDMUG_DATA_INSTALL_DIR "/usr/local/share/findmug"
#endif

namespace findmug::daemon {

std::string defaultConfigPath() { return FINDMUG_SYSCONF_DIR "/findmug/findmugd.yaml"; }
std::string defaultModelPath() { return FINDMUG_DATA_INSTALL_DIR "/models/findmug.fmf"; }

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

namespace {

std::string lcmUrlRule(const std::string& v) {
  if (!v.empty() && v.find("://") == std::string::npos) {
    return "an LCM URL such as udpm://239.255.76.67:7667?ttl=0, or empty";
  }
  return {};
}

// The `daemon:` section, on the core's settings mechanism (findmug/settings/settings.hpp).
const SettingsTable<DaemonConfig>& daemonSettings() {
  using D = DaemonConfig;
  static const SettingsTable<D> table = [] {
    SettingsTable<D> t("daemon");
    t.add(textSetting<D>(
        "daemon.source", [](D& d) -> std::string& { return d.source; },
        [](const std::string& v) {
          return v.empty() ? "a frame source spec, e.g. openni2 or dataset:/path" : "";
        },
        "frame source spec"));
    t.add(textSetting<D>(
        "daemon.lcm_url", [](D& d) -> std::string& { return d.lcm_url; }, lcmUrlRule,
        "output LCM provider"));
    t.add(textSetting<D>(
        "daemon.channel_suffix", [](D& d) -> std::string& { return d.channel_suffix; },
        [](const std::string& v) -> std::string {
          for (char c : v) {
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') {
              return "letters, digits and '_' only";
            }
          }
          return {};
        },
        "appended as _SUFFIX to every channel name"));
    t.add(textSetting<D>(
        "daemon.model_path", [](D& d) -> std::string& { return d.model_path; },
        [](const std::string& v) { return v.empty() ? "the path of a .fmf model file" : ""; },
        "forest model file"));
    t.add(integerSetting<D, int>(
        "daemon.queue_capacity", [](D& d) -> int& { return d.queue_capacity; }, 1, 64,
        "frames per queue between stages"));
    t.add(integerSetting<D, int>(
        "daemon.workers", [](D& d) -> int& { return d.workers; }, 0, 64,
        "segmentation workers; 0 = one per CPU core"));
    t.add(numberSetting<D, double>(
        "daemon.max_cpu_cores", [](D& d) -> double& { return d.max_cpu_cores; }, 0, 1024,
        "CPU budget in cores; 0 = none"));
    t.add(integerSetting<D, int>(
        "daemon.heap_keep_mb", [](D& d) -> int& { return d.heap_keep_mb; }, 0, 2047,
        "MB of freed heap malloc keeps for the next frames; 0 = glibc's defaults"));
    t.add(numberSetting<D, double>(
        "daemon.status_period_s", [](D& d) -> double& { return d.status_period_s; }, 0.05, 60,
        "FINDMUG_STATUS period"));
    t.add(numberSetting<D, double>(
        "daemon.stats_window_s", [](D& d) -> double& { return d.stats_window_s; }, 1, 3600,
        "window of the status rates and latency percentiles"));
    t.add(boolSetting<D>(
        "daemon.publish_confidence", [](D& d) -> bool& { return d.publish_confidence; },
        "per-pixel confidence in label images"));
    t.add(boolSetting<D>(
        "daemon.publish_tables", [](D& d) -> bool& { return d.publish_tables; },
        "publish FINDMUG_TABLES"));
    t.add(boolSetting<D>(
        "daemon.publish_color", [](D& d) -> bool& { return d.publish_color; },
        "the frame's colour image (JPEG) in each label image, for viewers"));
    t.add(integerSetting<D, int>(
        "daemon.color_jpeg_quality", [](D& d) -> int& { return d.color_jpeg_quality; }, 1, 100,
        "JPEG quality of daemon.publish_color"));
    t.add(boolSetting<D>(
        "daemon.exit_at_end_of_stream", [](D& d) -> bool& { return d.exit_at_end_of_stream; },
        "finite source exhausted: drain, publish, exit 0"));
    t.add(numberSetting<D, double>(
        "daemon.shutdown_grace_s", [](D& d) -> double& { return d.shutdown_grace_s; }, 0, 10,
        "on SIGTERM, wait this long for frames in flight"));
    t.add(numberSetting<D, double>(
        "daemon.source_timeout_s", [](D& d) -> double& { return d.source_timeout_s; }, 0.1, 3600,
        "a source silent this long counts as hung"));
    t.add(textSetting<D>(
        "daemon.log_level", [](D& d) -> std::string& { return d.log_level; },
        [](const std::string& v) -> std::string {
          if (v != "trace" && v != "debug" && v != "info" && v != "warn" && v != "error") {
            return "one of trace debug info warn error";
          }
          return {};
        },
        "trace, debug, info, warn, error"));
    t.add(boolSetting<D>(
        "daemon.command_input", [](D& d) -> bool& { return d.command_input; },
        "listen for command_t (reload_model) on FINDMUG_COMMAND"));
    t.add(textSetting<D>(
        "daemon.command_url", [](D& d) -> std::string& { return d.command_url; }, lcmUrlRule,
        "command LCM provider; empty = the output provider"));
    t.add(boolSetting<D>(
        "daemon.pose_input", [](D& d) -> bool& { return d.pose_input; },
        "listen for robot_pose_t"));
    t.add(textSetting<D>(
        "daemon.pose_url", [](D& d) -> std::string& { return d.pose_url; }, lcmUrlRule,
        "pose LCM provider; empty = the output provider"));
    t.add(numberSetting<D, double>(
        "daemon.pose_max_age_s", [](D& d) -> double& { return d.pose_max_age_s; }, 0, 10,
        "a frame takes the closest pose only this close in time"));
    t.add(numberSetting<D, double>(
        "daemon.pose_history_s", [](D& d) -> double& { return d.pose_history_s; }, 0.1, 3600,
        "poses kept for the lookup"));
    t.add(boolSetting<D>(
        "daemon.publish_table_map", [](D& d) -> bool& { return d.publish_table_map; },
        "publish FINDMUG_TABLE_MAP after each map update"));
    t.add(boolSetting<D>(
        "daemon.semantic_map", [](D& d) -> bool& { return d.semantic_map; },
        "fuse labelled frames with poses into the 3-D semantic map (semantic_map:)"));
    t.add(integerSetting<D, int>(
        "daemon.semantic_map_queue", [](D& d) -> int& { return d.semantic_map_queue; }, 1, 64,
        "frames waiting for the map stage (drop-oldest)"));
    t.add(numberSetting<D, double>(
        "daemon.semantic_map_publish_s", [](D& d) -> double& { return d.semantic_map_publish_s; },
        0, 3600, "FINDMUG_SEMANTIC_MAP and the map's tables at most this often, when changed"));
    t.add(boolSetting<D>(
        "daemon.semantic_map_fused_labels",
        [](D& d) -> bool& { return d.semantic_map_fused_labels; },
        "publish the map's labels projected into each frame on FINDMUG_LABELS"));
    t.add(textSetting<D>(
        "daemon.semantic_map_file", [](D& d) -> std::string& { return d.semantic_map_file; },
        nullptr, "the map is loaded from and saved to this file; empty = not kept"));
    t.add(numberSetting<D, double>(
        "daemon.semantic_map_save_s", [](D& d) -> double& { return d.semantic_map_save_s; }, 1,
        86400, "save the map this often (and at stop)"));
    t.add(textSetting<D>(
        "daemon.collect_dir", [](D& d) -> std::string& { return d.collect_dir; }, nullptr,
        "save frames worth labelling into this dataset folder; empty = off"));
    t.add(integerSetting<D, int>(
        "daemon.collect_max_frames", [](D& d) -> int& { return d.collect_max_frames; }, 1,
        1000000, "the collection folder holds at most this many frames"));
    t.add(numberSetting<D, double>(
        "daemon.collect_max_mb", [](D& d) -> double& { return d.collect_max_mb; }, 1, 1e7,
        "... and at most this many megabytes of rgb/ and depth/ PNGs"));
    t.add(numberSetting<D, double>(
        "daemon.collect_min_interval_s", [](D& d) -> double& { return d.collect_min_interval_s; },
        0, 86400, "automatic saves at most this often (frame capture time)"));
    t.add(numberSetting<D, double>(
        "daemon.collect_low_confidence", [](D& d) -> double& { return d.collect_low_confidence; },
        0, 1, "save a frame whose mean confidence is below this; 0 = off"));
    t.add(integerSetting<D, int>(
        "daemon.collect_flicker_changes", [](D& d) -> int& { return d.collect_flicker_changes; },
        0, 1000, "save when the table count changed this often within the window; 0 = off"));
    t.add(numberSetting<D, double>(
        "daemon.collect_flicker_window_s",
        [](D& d) -> double& { return d.collect_flicker_window_s; }, 0.1, 3600,
        "the table flicker window"));
    t.add(integerSetting<D, int>(
        "daemon.collect_queue", [](D& d) -> int& { return d.collect_queue; }, 1, 64,
        "frames waiting for the collection writer (full: the save is refused)"));
    return t;
  }();
  return table;
}

// The `check:` section: findmugd --check (check.hpp).
const SettingsTable<CheckConfig>& checkSettings() {
  using C = CheckConfig;
  static const SettingsTable<C> table = [] {
    SettingsTable<C> t("check");
    t.add(integerSetting<C, int>(
        "check.frames", [](C& c) -> int& { return c.frames; }, 1, 10000,
        "frames to read from the source"));
    t.add(numberSetting<C, double>(
        "check.timeout_s", [](C& c) -> double& { return c.timeout_s; }, 0.1, 3600,
        "give up waiting for them after this long"));
    t.add(numberSetting<C, double>(
        "check.min_valid_depth", [](C& c) -> double& { return c.min_valid_depth; }, 0, 1,
        "below this share of pixels with depth: a warning"));
    return t;
  }();
  return table;
}

// findmugd's sections join the registry parseConfig consults before main()
// runs, so every program linking this library (findmugd, its tests, the
// fuzzers) checks daemon and check keys while it reads the file.
[[maybe_unused]] const bool kSectionsRegistered = [] {
  cli::declareProjectSections();
  configSections().addSection("daemon", [](const std::string& key, const std::string& value) {
    daemonSettings().check(key, value);
  });
  configSections().addSection("check", [](const std::string& key, const std::string& value) {
    checkSettings().check(key, value);
  });
  return true;
}();

}  // namespace

DaemonConfig resolveDaemonConfig(Config& config) {
  DaemonConfig daemon;
  for (const auto& [key, value] : config.extra) {
    if (key.rfind("daemon.", 0) == 0) {
      daemonSettings().set(daemon, key, value);
    } else if (key.rfind("check.", 0) == 0) {
      checkSettings().set(daemon.check, key, value);
    }  // other owners' sections
  }
  // The core's table_map section: its keys, then consistency across them
  // (validateTableMapConfig names the key as table_map.KEY).
  daemon.table_map = resolveTableMapConfig(config);
  daemon.semantic_map_config = resolveSemanticMapConfig(config);
  for (const auto& [key, value] : daemonSettings().values(daemon)) config.extra[key] = value;
  for (const auto& [key, value] : checkSettings().values(daemon.check)) config.extra[key] = value;
  return daemon;
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
    if (name == "--check-config" || name == "--check") continue;
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
  if (command_line.config_path) {
    loaded.config = loadConfig(*command_line.config_path);
    loaded.origin = *command_line.config_path;
  } else if (std::filesystem::exists(defaultConfigPath())) {
    loaded.config = loadConfig(defaultConfigPath());
    loaded.origin = defaultConfigPath();
  } else {
    loaded.origin = "built-in defaults (no " + defaultConfigPath() + ")";
  }
  for (const auto& o : command_line.overrides) applyOverride(loaded.config, o);
  try {
    loaded.daemon = resolveDaemonConfig(loaded.config);
  } catch (const Error& e) {
    throw Error(loaded.origin + " + flags: " + e.what());
  }
  return loaded;
}

}  // namespace findmug::daemon
