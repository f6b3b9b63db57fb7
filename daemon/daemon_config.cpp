// findmugd settings: the `daemon:` section of the YAML file and the command line.
#include "findmug/daemon/daemon_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <thread>

#include "findmug/error.hpp"
#include "findmug/numbers.hpp"
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

[[noreturn]] void bad(const std::string& key, const std::string& value,
                      const std::string& expected) {
  throw Error("invalid value '" + value + "' for " + key + " (expected " + expected + ")");
}

long long toInt(const std::string& key, const std::string& v, long long lo, long long hi) {
  const auto out = parseInteger(v);
  if (!out || *out < lo || *out > hi) {
    bad(key, v, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return *out;
}

double toDouble(const std::string& key, const std::string& v, double lo, double hi) {
  const auto out = parseNumber(v);
  if (!out || *out < lo || *out > hi) {
    bad(key, v, "a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return *out;
}

bool toBool(const std::string& key, const std::string& v) {
  if (v == "true" || v == "yes" || v == "on" || v == "1") return true;
  if (v == "false" || v == "no" || v == "off" || v == "0") return false;
  bad(key, v, "true or false");
}

std::string fmt(double v) {
  std::string s = std::to_string(v);
  while (s.size() > 1 && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

// One daemon key: how to read it into DaemonConfig and how to print it back.
struct Key {
  std::function<void(DaemonConfig&, const std::string& key, const std::string& value)> set;
  std::function<std::string(const DaemonConfig&)> get;
};

const std::map<std::string, Key>& keys() {
  using D = DaemonConfig;
  static const std::map<std::string, Key> all = {
      {"daemon.source",
       {[](D& d, const std::string& k, const std::string& v) {
          if (v.empty()) bad(k, v, "a frame source spec, e.g. openni2 or dataset:/path");
          d.source = v;
        },
        [](const D& d) { return d.source; }}},
      {"daemon.lcm_url",
       {[](D& d, const std::string& k, const std::string& v) {
          if (!v.empty() && v.find("://") == std::string::npos) {
            bad(k, v, "an LCM URL such as udpm://239.255.76.67:7667?ttl=0, or empty");
          }
          d.lcm_url = v;
        },
        [](const D& d) { return d.lcm_url; }}},
      {"daemon.channel_suffix",
       {[](D& d, const std::string& k, const std::string& v) {
          for (char c : v) {
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') {
              bad(k, v, "letters, digits and '_' only");
            }
          }
          d.channel_suffix = v;
        },
        [](const D& d) { return d.channel_suffix; }}},
      {"daemon.model_path",
       {[](D& d, const std::string& k, const std::string& v) {
          if (v.empty()) bad(k, v, "the path of a .fmf model file");
          d.model_path = v;
        },
        [](const D& d) { return d.model_path; }}},
      {"daemon.queue_capacity",
       {[](D& d, const std::string& k, const std::string& v) {
          d.queue_capacity = static_cast<int>(toInt(k, v, 1, 64));
        },
        [](const D& d) { return std::to_string(d.queue_capacity); }}},
      {"daemon.workers",
       {[](D& d, const std::string& k, const std::string& v) {
          d.workers = static_cast<int>(toInt(k, v, 0, 64));
        },
        [](const D& d) { return std::to_string(d.workers); }}},
      {"daemon.max_cpu_cores",
       {[](D& d, const std::string& k, const std::string& v) {
          d.max_cpu_cores = toDouble(k, v, 0, 1024);
        },
        [](const D& d) { return fmt(d.max_cpu_cores); }}},
      {"daemon.heap_keep_mb",
       {[](D& d, const std::string& k, const std::string& v) {
          d.heap_keep_mb = static_cast<int>(toInt(k, v, 0, 2047));
        },
        [](const D& d) { return std::to_string(d.heap_keep_mb); }}},
      {"daemon.status_period_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.status_period_s = toDouble(k, v, 0.05, 60);
        },
        [](const D& d) { return fmt(d.status_period_s); }}},
      {"daemon.stats_window_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.stats_window_s = toDouble(k, v, 1, 3600);
        },
        [](const D& d) { return fmt(d.stats_window_s); }}},
      {"daemon.publish_confidence",
       {[](D& d, const std::string& k, const std::string& v) {
          d.publish_confidence = toBool(k, v);
        },
        [](const D& d) { return std::string(d.publish_confidence ? "true" : "false"); }}},
      {"daemon.publish_tables",
       {[](D& d, const std::string& k, const std::string& v) { d.publish_tables = toBool(k, v); },
        [](const D& d) { return std::string(d.publish_tables ? "true" : "false"); }}},
      {"daemon.exit_at_end_of_stream",
       {[](D& d, const std::string& k, const std::string& v) {
          d.exit_at_end_of_stream = toBool(k, v);
        },
        [](const D& d) { return std::string(d.exit_at_end_of_stream ? "true" : "false"); }}},
      {"daemon.shutdown_grace_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.shutdown_grace_s = toDouble(k, v, 0, 10);
        },
        [](const D& d) { return fmt(d.shutdown_grace_s); }}},
      {"daemon.source_timeout_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.source_timeout_s = toDouble(k, v, 0.1, 3600);
        },
        [](const D& d) { return fmt(d.source_timeout_s); }}},
      {"daemon.log_level",
       {[](D& d, const std::string& k, const std::string& v) {
          if (v != "trace" && v != "debug" && v != "info" && v != "warn" && v != "error") {
            bad(k, v, "one of trace debug info warn error");
          }
          d.log_level = v;
        },
        [](const D& d) { return d.log_level; }}},
      {"daemon.pose_input",
       {[](D& d, const std::string& k, const std::string& v) { d.pose_input = toBool(k, v); },
        [](const D& d) { return std::string(d.pose_input ? "true" : "false"); }}},
      {"daemon.pose_url",
       {[](D& d, const std::string& k, const std::string& v) {
          if (!v.empty() && v.find("://") == std::string::npos) {
            bad(k, v, "an LCM URL such as udpm://239.255.76.67:7667?ttl=0, or empty");
          }
          d.pose_url = v;
        },
        [](const D& d) { return d.pose_url; }}},
      {"daemon.pose_max_age_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.pose_max_age_s = toDouble(k, v, 0, 10);
        },
        [](const D& d) { return fmt(d.pose_max_age_s); }}},
      {"daemon.pose_history_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.pose_history_s = toDouble(k, v, 0.1, 3600);
        },
        [](const D& d) { return fmt(d.pose_history_s); }}},
      {"daemon.publish_table_map",
       {[](D& d, const std::string& k, const std::string& v) {
          d.publish_table_map = toBool(k, v);
        },
        [](const D& d) { return std::string(d.publish_table_map ? "true" : "false"); }}},
  };
  return all;
}

// The table_map section: findmug::TableMapConfig, one key per field. Ranges
// here only keep the numbers sane; validateTableMapConfig (core) has the
// final word on consistency.
const std::map<std::string, Key>& tableMapKeys() {
  using D = DaemonConfig;
  static const std::map<std::string, Key> all = {
      {"table_map.confirm_sightings",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.confirm_sightings = static_cast<int>(toInt(k, v, 1, 1000));
        },
        [](const D& d) { return std::to_string(d.table_map.confirm_sightings); }}},
      {"table_map.forget_misses",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.forget_misses = static_cast<int>(toInt(k, v, 1, 1000));
        },
        [](const D& d) { return std::to_string(d.table_map.forget_misses); }}},
      {"table_map.tentative_timeout_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.tentative_timeout_s = toDouble(k, v, 0, 86400);
        },
        [](const D& d) { return fmt(d.table_map.tentative_timeout_s); }}},
      {"table_map.match_gap_m",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.match_gap_m = static_cast<float>(toDouble(k, v, 0, 5));
        },
        [](const D& d) { return fmt(d.table_map.match_gap_m); }}},
      {"table_map.match_height_m",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.match_height_m = static_cast<float>(toDouble(k, v, 0, 2));
        },
        [](const D& d) { return fmt(d.table_map.match_height_m); }}},
      {"table_map.view_half_angle_rad",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.view_half_angle_rad = static_cast<float>(toDouble(k, v, 0, 3.14159));
        },
        [](const D& d) { return fmt(d.table_map.view_half_angle_rad); }}},
      {"table_map.view_min_range_m",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.view_min_range_m = static_cast<float>(toDouble(k, v, 0, 100));
        },
        [](const D& d) { return fmt(d.table_map.view_min_range_m); }}},
      {"table_map.view_max_range_m",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.view_max_range_m = static_cast<float>(toDouble(k, v, 0, 100));
        },
        [](const D& d) { return fmt(d.table_map.view_max_range_m); }}},
      {"table_map.max_observations",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.max_observations = static_cast<int>(toInt(k, v, 1, 1000));
        },
        [](const D& d) { return std::to_string(d.table_map.max_observations); }}},
      {"table_map.position_match_m",
       {[](D& d, const std::string& k, const std::string& v) {
          d.table_map.position_match_m = static_cast<float>(toDouble(k, v, 0, 5));
        },
        [](const D& d) { return fmt(d.table_map.position_match_m); }}},
  };
  return all;
}

// The check section: findmugd --check (check.hpp).
const std::map<std::string, Key>& checkKeys() {
  using D = DaemonConfig;
  static const std::map<std::string, Key> all = {
      {"check.frames",
       {[](D& d, const std::string& k, const std::string& v) {
          d.check.frames = static_cast<int>(toInt(k, v, 1, 10000));
        },
        [](const D& d) { return std::to_string(d.check.frames); }}},
      {"check.timeout_s",
       {[](D& d, const std::string& k, const std::string& v) {
          d.check.timeout_s = toDouble(k, v, 0.1, 3600);
        },
        [](const D& d) { return fmt(d.check.timeout_s); }}},
      {"check.min_valid_depth",
       {[](D& d, const std::string& k, const std::string& v) {
          d.check.min_valid_depth = toDouble(k, v, 0, 1);
        },
        [](const D& d) { return fmt(d.check.min_valid_depth); }}},
  };
  return all;
}

std::string keyList(const std::map<std::string, Key>& keys) {
  std::string known;
  for (const auto& [name, k] : keys) known += (known.empty() ? "" : ", ") + name;
  return known;
}

}  // namespace

DaemonConfig resolveDaemonConfig(Config& config) {
  DaemonConfig daemon;
  for (const auto& [key, value] : config.extra) {
    const std::map<std::string, Key>* section = nullptr;
    std::string section_name;
    if (key.rfind("daemon.", 0) == 0) {
      section = &keys();
      section_name = "daemon";
    } else if (key.rfind("table_map.", 0) == 0) {
      section = &tableMapKeys();
      section_name = "table_map";
    } else if (key.rfind("check.", 0) == 0) {
      section = &checkKeys();
      section_name = "check";
    } else {
      continue;  // other owners' sections
    }
    const auto it = section->find(key);
    if (it == section->end()) {
      throw Error("unknown setting '" + key + "' (" + section_name +
                  " keys: " + keyList(*section) + ")");
    }
    it->second.set(daemon, key, value);
  }
  // Consistency across keys (e.g. view_min_range_m below view_max_range_m);
  // the message names the key as table_map.KEY.
  validateTableMapConfig(daemon.table_map);
  for (const auto& [name, k] : keys()) config.extra[name] = k.get(daemon);
  for (const auto& [name, k] : tableMapKeys()) config.extra[name] = k.get(daemon);
  for (const auto& [name, k] : checkKeys()) config.extra[name] = k.get(daemon);
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
