// findmug/daemon/daemon_config.hpp — findmugd's own settings and command line.
//
// The YAML file holds the core sections (parsed by findmug::parseConfig) and a
// `daemon:` section whose keys arrive in Config::extra as "daemon.NAME". This
// file defines, validates and documents those keys (daemon/findmugd.yaml is
// the annotated default file); an unknown daemon key or a bad value is a
// findmug::Error naming the key, and start-up stops.
//
// The `table_map:` section (Config::extra "table_map.NAME") configures the
// persistent table map (findmug::TableMapConfig); the core owns and checks it
// (findmug::resolveTableMapConfig), resolveDaemonConfig puts it into DaemonConfig.
// This library registers `daemon` and `check` in findmug::configSections()
// when it is loaded (settings.hpp), so parseConfig checks their keys as it reads.
//
// Precedence, lowest first: built-in defaults < YAML file < command-line
// flags. daemon.lcm_url left empty means $LCM_DEFAULT_URL, then liblcm's
// own default.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "findmug/map/semantic_map.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/settings/config.hpp"

namespace findmug::daemon {

// Compiled-in default locations (CMake passes the install prefix).
std::string defaultConfigPath();  // /etc/findmug/findmugd.yaml
std::string defaultModelPath();   // <prefix>/share/findmug/models/findmug.fmf

// `findmugd --check` (the `check:` section): how long to look at the source.
struct CheckConfig {
  int frames = 10;               // frames to read from the source
  double timeout_s = 10.0;       // give up waiting for them after this long
  double min_valid_depth = 0.5;  // below this share of pixels with depth: a warning
};

struct DaemonConfig {
  std::string source = "openni2";  // frame source spec, see findmug::io::makeFrameSource
  std::string lcm_url;             // output LCM provider; "" = $LCM_DEFAULT_URL / liblcm default
  std::string channel_suffix;      // appended as "_SUFFIX" to every channel name
  std::string model_path = defaultModelPath();
  int queue_capacity = 2;             // per queue between stages (frames)
  int workers = 0;                    // segmentation workers; 0 = one per CPU core
  // CPU budget in cores; 0 = none. Below 2: every stage (decoding included)
  // runs one after another on the source's thread; from 2: the threaded
  // pipeline with at most floor(max_cpu_cores) - 1 segmentation workers.
  double max_cpu_cores = 0.0;
  // Freed memory glibc keeps in the heap for the next frame instead of
  // returning it to the kernel (MB; 0 = glibc's own thresholds). A frame's
  // buffers are then reused instead of being page-faulted in and zeroed again.
  int heap_keep_mb = 256;
  double status_period_s = 1.0;       // FINDMUG_STATUS period
  double stats_window_s = 10.0;       // window of the status rates and latency percentiles
  bool publish_confidence = true;     // include per-pixel confidence in label images
  bool publish_tables = true;         // publish FINDMUG_TABLES
  // The frame's colour image (JPEG) in each label image, for viewers (findmug-web)
  // on sources that do not publish FINDMUG_RGBD (datasets, logs, PCD, devices).
  bool publish_color = false;
  int color_jpeg_quality = 80;        // 1..100
  bool exit_at_end_of_stream = true;  // finite source exhausted: drain, publish, exit 0
  double shutdown_grace_s = 1.0;      // on SIGTERM, wait this long for frames in flight
  // A source that stays inside next() this long while it reports "running"
  // (no frame, no error, no state change) counts as hung: logged, and the
  // watchdog is no longer fed. Paced file sources get at least 3 periods.
  double source_timeout_s = 10.0;
  std::string log_level = "info";     // trace, debug, info, warn, error

  // Commands (command_t on FINDMUG_COMMAND: reload_model), command_input.hpp.
  bool command_input = true;       // listen for command_t
  std::string command_url;         // "" = the output provider (see effectiveCommandUrl)

  // Robot pose input (FINDMUG_ROBOT_POSE) and the table map (FINDMUG_TABLE_MAP).
  bool pose_input = true;          // listen for robot_pose_t
  std::string pose_url;            // "" = the output provider (see effectivePoseUrl)
  double pose_max_age_s = 0.2;     // a frame takes the closest pose only this close in time
  double pose_history_s = 5.0;     // poses kept for the lookup (must cover the latency)
  bool publish_table_map = true;   // publish FINDMUG_TABLE_MAP after each map update
  TableMapConfig table_map;        // the `table_map:` section
  // The fused 3-D semantic map (semantic_map_stage.hpp): off by default; needs poses.
  bool semantic_map = false;
  int semantic_map_queue = 2;              // frames waiting for the map thread (drop-oldest)
  double semantic_map_publish_s = 2.0;     // map message and map tables at most this often
  bool semantic_map_fused_labels = false;  // FINDMUG_LABELS carries the map's labels
  std::string semantic_map_file;           // load at start, save periodically and at stop
  double semantic_map_save_s = 60.0;
  SemanticMapConfig semantic_map_config;   // the `semantic_map:` section
  // Frames worth labelling saved into a dataset folder (frame_collector.hpp); off
  // while collect_dir is empty.
  std::string collect_dir;
  int collect_max_frames = 500;           // the folder's bound, frames ...
  double collect_max_mb = 2000.0;         // ... and megabytes (its rgb/ and depth/ PNGs)
  double collect_min_interval_s = 10.0;   // automatic saves at most this often (capture time)
  double collect_low_confidence = 0.0;    // save when a frame's mean confidence is below (0: off)
  int collect_flicker_changes = 0;        // save when the table count changes this often ...
  double collect_flicker_window_s = 5.0;  // ... within this many seconds (0 changes: off)
  int collect_queue = 2;                  // frames waiting for the writer thread
  CheckConfig check;               // the `check:` section (findmugd --check only)

  // Channel names with the suffix applied.
  std::string channel(const std::string& base) const {
    return channel_suffix.empty() ? base : base + "_" + channel_suffix;
  }
  // Number of segmentation workers after resolving 0 to the core count and
  // applying max_cpu_cores.
  int effectiveWorkers() const;
  // max_cpu_cores asks for one processing thread (see above).
  bool singleThreaded() const { return max_cpu_cores > 0.0 && max_cpu_cores < 2.0; }
};

// Reads and validates every "daemon.*", "check.*" and "table_map.*" entry of
// `config.extra`, then writes the effective values back into it (so
// dumpConfig shows all of them).
// Throws findmug::Error naming the key for unknown keys and bad values.
DaemonConfig resolveDaemonConfig(Config& config);

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
  bool help = false;
  bool version = false;  // --version: print "findmugd VERSION", exit
};

// Throws findmug::Error for unknown flags or missing values.
CommandLine parseCommandLine(const std::vector<std::string>& args);
std::string usage();
// The flags that stand for one daemon setting ("--model" -> "daemon.model_path").
const std::vector<std::pair<std::string, std::string>>& daemonFlagShortcuts();

// Loads the file (the default one may be absent: then built-in defaults),
// applies the overrides and resolves the daemon section.
struct LoadedConfig {
  Config config;
  DaemonConfig daemon;
  std::string origin;  // which file was read, or "built-in defaults"
};
LoadedConfig loadDaemonConfig(const CommandLine& command_line);

}  // namespace findmug::daemon
