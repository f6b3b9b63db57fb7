// program_settings.hpp — the settings of the project's programs that share one config
// file (daemon/findmugd.yaml): findmugd's `daemon:` and `check:` sections, findmug-web's
// `web:`, as plain structs and their settings tables (findmug/settings/settings.hpp).
//
// Here, beside the command line every program links, and not in daemon/ or clients/web/,
// so that findmug-train, findmug-eval, the clients and findmug-web validate the whole
// shared file with the real tables without linking the daemon: a typo in `daemon.*` is
// refused by every program. No LCM, no threads: data and parsing only.
#pragma once

#include <string>

#include "findmug/map/object_map.hpp"
#include "findmug/map/object_search.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/objects/object_matcher.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"

namespace findmug::daemon {

// Compiled-in default location of the model (CMake passes the install prefix):
// <prefix>/share/findmug/models/findmug.fmf.
std::string defaultModelPath();

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
  bool publish_tables = true;         // publish FINDMUG_TABLES and FINDMUG_OBJECTS
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
  // One CSV row per published frame: where its time went, queue by queue
  // (frame_trace.hpp; what tests/bench/daemon_bench.sh reads). "" = off.
  std::string frame_trace_file;

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
  // The fused 3-D semantic map (semantic_map_sink.hpp): off by default; needs poses.
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
  // Taught objects (*.fmo, object_library.hpp) the daemon looks for; off while empty.
  std::string objects_dir;
  int objects_queue = 2;            // frames waiting for the object worker (drop-oldest)
  bool publish_object_map = true;   // publish FINDMUG_OBJECT_MAP after each object map update
  // The objects on the tables named, mapped and found (object_search_sink.hpp): the
  // `object_matcher:`, `object_map:` and `object_search:` sections.
  ObjectMatcherConfig object_matcher;
  ObjectMapConfig object_map;
  ObjectSearchConfig object_search;
  CheckConfig check;               // the `check:` section (findmugd --check only)

  // Number of segmentation workers after resolving 0 to the core count and
  // applying max_cpu_cores (defined in findmug_daemon: only findmugd runs workers).
  int effectiveWorkers() const;
  // max_cpu_cores asks for one processing thread (see above).
  bool singleThreaded() const { return max_cpu_cores > 0.0 && max_cpu_cores < 2.0; }
};

const SettingsTable<DaemonConfig>& daemonSettings();  // daemon.*
const SettingsTable<CheckConfig>& checkSettings();    // check.*

// Binds the `daemon:`, `check:`, `table_map:` and `semantic_map:` sections to `daemon`
// (the last two with their cross-key checks).
void bindDaemonSettings(SettingsSchema& schema, DaemonConfig& daemon);

// findmugd's settings schema: the segmenter's sections bound to `config`, its own
// (bindDaemonSettings) to `daemon`, other programs' sections of the file accepted
// (cli::acceptSharedFileSettings). Also for the tools that read findmugd.yaml as findmugd does.
SettingsSchema daemonSchema(Config& config, DaemonConfig& daemon);

}  // namespace findmug::daemon

namespace findmug::web {

struct WebConfig {
  // Address to listen on. 127.0.0.1 (or ::1, localhost) serves this machine only and
  // needs no token; any other address requires token_file.
  std::string bind = "127.0.0.1";
  int port = 8088;
  // File holding the access token (first line, at least 16 characters); "" = none.
  std::string token_file;
  // Largest request body accepted, bytes (413 above it, on every endpoint).
  long long max_body_bytes = 4LL * 1024 * 1024;
  // How far back the status plots reach, seconds.
  double history_s = 300.0;
  // Where the page's HTML/JS/CSS are ("" = the installed folder).
  std::string static_dir;
  // The model whose prediction the Label page starts from ("" = none); its cloud.*,
  // normals.*, oversegmentation.* and features.* settings must be the config's, as for findmugd.
  std::string model_path;
  // NYU's camera_rotations_NYU.txt, for ground.source=gravity on frames named by their
  // NYU index ("" = none).
  std::string nyu_rotations;
  // The Retrain page (retrain.hpp): the tools it runs, where its jobs write their model
  // and report ("" = the page is off), the model file findmugd loads (daemon.model_path;
  // "" = no Install), findmug-eval's folds.
  std::string train_program = "findmug-train";
  std::string eval_program = "findmug-eval";
  std::string jobs_dir;
  std::string install_path;
  int retrain_folds = 5;
};

const SettingsTable<WebConfig>& webSettings();  // web.*

}  // namespace findmug::web

namespace findmug::cli {

// Accepts, into defaults the schema owns, every table of the shared config file that
// `schema` has not bound: the segmenter's sections, the offline tools' (training, degrade,
// table_metrics), table_map, semantic_map, daemon, check, web. A program binds the tables it
// uses, then calls this, so that the other programs' sections are checked key by key but not
// used.
void acceptSharedFileSettings(SettingsSchema& schema);

}  // namespace findmug::cli
