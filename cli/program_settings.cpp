// The settings of the programs sharing one config file; see program_settings.hpp.
#include "program_settings.hpp"

#include <cctype>

#include "findmug/common/error.hpp"

#ifndef FINDMUG_DATA_INSTALL_DIR
#define FINDMUG_DATA_INSTALL_DIR "/usr/local/share/findmug"
#endif

namespace findmug::daemon {

std::string defaultModelPath() { return FINDMUG_DATA_INSTALL_DIR "/models/findmug.fmf"; }

namespace {

std::string lcmUrlRule(const std::string& v) {
  if (!v.empty() && v.find("://") == std::string::npos) {
    return "an LCM URL such as udpm://239.255.76.67:7667?ttl=0, or empty";
  }
  return {};
}

}  // namespace

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
        "frames at the pipeline entry; results in the publish queue besides one per worker"));
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
        "publish FINDMUG_TABLES and FINDMUG_OBJECTS"));
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
    t.add(textSetting<D>(
        "daemon.frame_trace_file", [](D& d) -> std::string& { return d.frame_trace_file; },
        nullptr, "one CSV row per published frame: its time in each queue and step; empty = off"));
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
        "frames waiting for the map sink (drop-oldest)"));
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
    t.add(textSetting<D>(
        "daemon.objects_dir", [](D& d) -> std::string& { return d.objects_dir; }, nullptr,
        "taught objects (*.fmo from findmug-teach) to look for, re-read when changed; empty = off"));
    t.add(integerSetting<D, int>(
        "daemon.objects_queue", [](D& d) -> int& { return d.objects_queue; }, 1, 64,
        "frames waiting for the object worker (matching, object map; drop-oldest)"));
    t.add(boolSetting<D>(
        "daemon.publish_object_map", [](D& d) -> bool& { return d.publish_object_map; },
        "publish FINDMUG_OBJECT_MAP after each object map update"));
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

void bindDaemonSettings(SettingsSchema& schema, DaemonConfig& daemon) {
  schema.bind(daemonSettings(), daemon);
  schema.bind(checkSettings(), daemon.check);
  schema.bind(tableMapSettings(), daemon.table_map, validateTableMapConfig);
  schema.bind(semanticMapSettings(), daemon.semantic_map_config, validateSemanticMapConfig);
  schema.bind(objectMatcherSettings(), daemon.object_matcher, validateObjectMatcherConfig);
  schema.bind(objectMapSettings(), daemon.object_map, validateObjectMapConfig);
  schema.bind(objectSearchSettings(), daemon.object_search, validateObjectSearchConfig);
}

SettingsSchema daemonSchema(Config& config, DaemonConfig& daemon) {
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindDaemonSettings(schema, daemon);
  cli::acceptSharedFileSettings(schema);
  return schema;
}

}  // namespace findmug::daemon

namespace findmug::web {

const SettingsTable<WebConfig>& webSettings() {
  static const SettingsTable<WebConfig> table = [] {
    using W = WebConfig;
    SettingsTable<W> t("web");
    t.add(textSetting<W>(
        "web.bind", [](W& w) -> std::string& { return w.bind; },
        [](const std::string& v) {
          return v.empty() || v.find_first_of(" \t/") != std::string::npos
                     ? std::string("an IP address or host name")
                     : std::string();
        },
        "address to listen on; other than 127.0.0.1/::1/localhost needs web.token_file"));
    t.add(integerSetting<W, int>(
        "web.port", [](W& w) -> int& { return w.port; }, 1, 65535, "TCP port"));
    t.add(textSetting<W>(
        "web.token_file", [](W& w) -> std::string& { return w.token_file; }, {},
        "file holding the access token (required off loopback)"));
    t.add(integerSetting<W, long long>(
        "web.max_body_bytes", [](W& w) -> long long& { return w.max_body_bytes; }, 1024,
        256LL * 1024 * 1024, "largest request body; 413 above it"));
    t.add(numberSetting<W, double>(
        "web.history_s", [](W& w) -> double& { return w.history_s; }, 10, 3600,
        "how far back the status plots reach"));
    t.add(textSetting<W>(
        "web.static_dir", [](W& w) -> std::string& { return w.static_dir; }, {},
        "folder of the page's HTML/JS/CSS; empty = the installed one"));
    t.add(textSetting<W>(
        "web.model_path", [](W& w) -> std::string& { return w.model_path; }, {},
        "model the Label page's prediction comes from; empty = none"));
    t.add(textSetting<W>(
        "web.nyu_rotations", [](W& w) -> std::string& { return w.nyu_rotations; }, {},
        "NYU's camera_rotations_NYU.txt for frames named by NYU index; empty = none"));
    t.add(textSetting<W>(
        "web.train_program", [](W& w) -> std::string& { return w.train_program; }, {},
        "findmug-train to run from the Retrain page (a name on PATH or a path)"));
    t.add(textSetting<W>(
        "web.eval_program", [](W& w) -> std::string& { return w.eval_program; }, {},
        "findmug-eval to run from the Retrain page"));
    t.add(textSetting<W>(
        "web.jobs_dir", [](W& w) -> std::string& { return w.jobs_dir; }, {},
        "where Retrain jobs write models and reports; empty = no Retrain page"));
    t.add(textSetting<W>(
        "web.install_path", [](W& w) -> std::string& { return w.install_path; }, {},
        "Install copies the trained model here (findmugd's daemon.model_path); empty = off"));
    t.add(integerSetting<W, int>(
        "web.retrain_folds", [](W& w) -> int& { return w.retrain_folds; }, 2, 50,
        "findmug-eval --folds on the Retrain page"));
    return t;
  }();
  return table;
}

}  // namespace findmug::web

namespace findmug::cli {

namespace {
// Accepts `table` unless the schema binds one of its sections already.
template <typename T>
void acceptUnbound(SettingsSchema& schema, const SettingsTable<T>& table,
                   std::function<void(const T&)> validate = {}) {
  for (const auto& section : table.sections()) {
    if (schema.has(section)) return;
  }
  schema.accept(table, std::move(validate));
}
}  // namespace

void acceptSharedFileSettings(SettingsSchema& schema) {
  acceptUnbound<SegmenterConfig>(schema, segmenterSettings(), validateSegmenterConfig);
  acceptUnbound<OfflineConfig>(schema, offlineSettings());
  acceptUnbound<TableMapConfig>(schema, tableMapSettings(), validateTableMapConfig);
  acceptUnbound<SemanticMapConfig>(schema, semanticMapSettings(), validateSemanticMapConfig);
  acceptUnbound<ObjectMatcherConfig>(schema, objectMatcherSettings(), validateObjectMatcherConfig);
  acceptUnbound<ObjectMapConfig>(schema, objectMapSettings(), validateObjectMapConfig);
  acceptUnbound<ObjectSearchConfig>(schema, objectSearchSettings(), validateObjectSearchConfig);
  acceptUnbound(schema, daemon::daemonSettings());
  acceptUnbound(schema, daemon::checkSettings());
  acceptUnbound(schema, web::webSettings());
}

}  // namespace findmug::cli
