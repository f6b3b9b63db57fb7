// semantic_map_walk — per-frame labels and tables against the fused semantic map, on
// rendered walks through synthetic apartments (findmug_synth) with exact ground truth.
//
// For each seed: an apartment, a camera path that visits every table from two sides,
// Kinect-like depth noise, each frame labelled by a model (default models/findmug.fmf, the
// NYU-only model: realistic errors on rendered frames), then fused into a SemanticMap at
// its pose (robot pose, optionally with noise, composed with the frame's camera mount, as
// findmugd does). Prints, per seed, Markdown rows:
//   * label accuracy over the pixels with a ground-truth label and a label: the frame's
//     own; the map's labels projected into the frame right after fusing it (causal); and
//     the final map's labels projected into every frame;
//   * tables at the end against the generator's: the persistent per-frame table map
//     (TableMap, FINDMUG_TABLE_MAP today) and the tables from the fused map; a table
//     matches a true one when its box centre lies on the true top (one to one);
//   * the map sink's CPU per frame (integrate, thread CPU time, median), tables() CPU,
//     voxels and memory after the walk, and the map message's size (zlib);
//   * the search positions' error: for the tables matched to a true one, the mean over
//     their search positions (reachable or not) of |distance to the true top's edge - the
//     tables.safety_distance_m the stage aims for|;
//   * each frame's own tables (FINDMUG_TABLES, moved into the map by the frame's pose):
//     precision (detections on a true top), recall (of the tables visible in the frame:
//     1 % of its pixels show the table) and search-position error, over the walk;
//   * then, per quarter of each walk, how it grows: frame and causal fused accuracy over the
//     quarter's frames, and the tables of both maps against the truth at its end.
// --move-table K: half-way through the walk table K (modulo the scene's tables; or the next
// one that has a free spot: 0.7 m from walls and furniture) is carried to the free spot
// farthest from it (synth::freeSpotForTable, synth::moveTable, with what
// stands on it), and the second half of the path is planned in the changed room, visiting
// the old place as if a table still stood there (--revisit 0: the tables only). The truth
// is the room as it is at each frame; a further table prints how many frames after the move
// saw the old place (its top's centre in the image within semantic_map.max_range_m) and,
// per map, after how many frames since the move the old place held no table any more and
// the new one held one.
//
//   semantic_map_walk [--config daemon/findmugd.yaml] [--model models/findmug.fmf]
//                     [--seeds 1,2,3] [--frames 60] [--fps 2] [--move-table -1] [--revisit 1]
//                     [--pose-noise-m 0] [--pose-noise-deg 0] [--verbose 1]
// --verbose 1 also lists every true table and every table of both maps at the end (stderr).
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/synth/synth.hpp"
#include "findmug_cli.hpp"
#include "program_settings.hpp"

namespace {

using namespace findmug;

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Accuracy {
  long correct = 0, total = 0;
  void add(const LabelImage& labels, const std::vector<std::uint8_t>& truth) {
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (truth[i] == kVoidLabel || labels.labels[i] == kVoidLabel) continue;
      ++total;
      correct += labels.labels[i] == truth[i];
    }
  }
  double value() const { return total ? static_cast<double>(correct) / total : 0.0; }
};

struct TableScore {
  int detected = 0, truth = 0, matched = 0;
  double error_sum = 0.0;
  double search_error_sum = 0.0;  // |distance to the true edge - safety distance|
  int search_positions = 0;
  void add(const TableScore& o) {
    detected += o.detected, truth += o.truth, matched += o.matched;
    error_sum += o.error_sum, search_error_sum += o.search_error_sum;
    search_positions += o.search_positions;
  }
};

// Map-frame tables against the true tables of `truths`: one to one, a box centre on a true
// top; the matched tables' reachable search positions against the true edge.
TableScore score(const std::vector<TableCluster>& tables,
                 const std::vector<const synth::TableTruth*>& truths, double safety_distance_m) {
  TableScore s;
  s.detected = static_cast<int>(tables.size());
  s.truth = static_cast<int>(truths.size());
  std::vector<bool> used(tables.size(), false);
  for (const synth::TableTruth* t : truths) {
    int best = -1;
    double best_d = 1e9;
    for (std::size_t k = 0; k < tables.size(); ++k) {
      const Eigen::Vector2d centre = tables[k].center.cast<double>();
      if (used[k] || synth::signedDistanceToTop(*t, centre) >= 0.0) continue;
      const double d = (centre - t->center_xy).norm();
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(k);
      }
    }
    if (best < 0) continue;
    used[static_cast<std::size_t>(best)] = true;
    ++s.matched;
    s.error_sum += best_d;
    for (const SearchPosition& p : tables[static_cast<std::size_t>(best)].search_positions) {
      s.search_error_sum +=
          std::abs(synth::signedDistanceToTop(*t, p.xy.cast<double>()) - safety_distance_m);
      ++s.search_positions;
    }
  }
  return s;
}

std::vector<const synth::TableTruth*> allTables(const synth::SynthScene& scene) {
  std::vector<const synth::TableTruth*> out;
  for (const synth::TableTruth& t : scene.tables) out.push_back(&t);
  return out;
}

TableScore score(const std::vector<TableCluster>& tables, const synth::SynthScene& scene,
                 double safety_distance_m) {
  return score(tables, allTables(scene), safety_distance_m);
}

// "P, R, centre error, search-position error" (n/a without matches).
std::string pr(const TableScore& s) {
  char buf[128];
  if (s.matched == 0) {
    std::snprintf(buf, sizeof(buf), "0/%d, 0/%d, -, -", s.detected, s.truth);
  } else if (s.search_positions == 0) {
    std::snprintf(buf, sizeof(buf), "%d/%d, %d/%d, %.3f, -", s.matched, s.detected, s.matched,
                  s.truth, s.error_sum / s.matched);
  } else {
    std::snprintf(buf, sizeof(buf), "%d/%d, %d/%d, %.3f, %.3f", s.matched, s.detected, s.matched,
                  s.truth, s.error_sum / s.matched, s.search_error_sum / s.search_positions);
  }
  return buf;
}

// Whether a table's box centre lies on the top of `truth`.
bool anyOn(const std::vector<TableCluster>& tables, const synth::TableTruth& truth) {
  for (const TableCluster& t : tables) {
    if (synth::signedDistanceToTop(truth, t.center.cast<double>()) < 0.0) return true;
  }
  return false;
}

// Whether the camera saw the table's place: its top's centre in the image, in front of
// the camera and within `range_m` (the map's max_range_m: farther points are not fused).
bool placeInView(const synth::TableTruth& table, const synth::CameraPose& pose,
                 const CameraIntrinsics& k, int width, int height, double range_m) {
  const Eigen::Vector3d world(table.center_xy.x(), table.center_xy.y(), table.height);
  const Eigen::Vector3d c = synth::cameraToWorld(pose).inverse() * world;
  if (c.z() < 0.3 || c.norm() > range_m) return false;
  const double u = k.fx * c.x() / c.z() + k.cx, v = k.fy * c.y() / c.z() + k.cy;
  return u >= 0 && v >= 0 && u < width && v < height;
}

std::vector<TableCluster> fusedClusters(SemanticMap& map) {
  std::vector<TableCluster> out;
  for (const FusedTable& t : map.tables()) out.push_back(t.table);
  return out;
}

// After the move: the first frame (counted from the move, 1 = the first frame after it)
// when the old place holds no table, and when the new place holds one; 0 = not yet.
struct MoveEvents {
  int old_gone = 0, new_found = 0;
  int old_in_view = 0;  // frames after the move that saw the old place (placeInView)
  void update(const std::vector<TableCluster>& tables, const synth::TableTruth& before,
              const synth::TableTruth& after, int frames_since_move) {
    if (old_gone == 0 && !anyOn(tables, before)) old_gone = frames_since_move;
    if (new_found == 0 && anyOn(tables, after)) new_found = frames_since_move;
  }
  std::string text(bool old_gone_at_end, bool new_found_at_end) const {
    auto one = [](int frame, bool at_end) {
      if (frame == 0) return std::string("never");
      return std::to_string(frame) + (at_end ? "" : " (not at the end)");
    };
    return one(old_gone, old_gone_at_end) + " | " + one(new_found, new_found_at_end);
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string config_path = "daemon/findmugd.yaml", model_path = "models/findmug.fmf";
  std::vector<std::uint64_t> seeds = {1, 2, 3};
  int frames = 60;
  double fps = 2.0, noise_m = 0.0, noise_deg = 0.0;
  bool verbose = false;
  int move_table = -1;
  bool revisit = true;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--config") {
      config_path = value;
    } else if (flag == "--model") {
      model_path = value;
    } else if (flag == "--seeds") {
      seeds.clear();
      std::stringstream in(value);
      std::string item;
      while (std::getline(in, item, ',')) seeds.push_back(std::stoull(item));
    } else if (flag == "--frames") {
      frames = std::stoi(value);
    } else if (flag == "--fps") {
      fps = std::stod(value);
    } else if (flag == "--pose-noise-m") {
      noise_m = std::stod(value);
    } else if (flag == "--revisit") {
      revisit = value == "1";
    } else if (flag == "--move-table") {
      move_table = std::stoi(value);
    } else if (flag == "--verbose") {
      verbose = value == "1";
    } else if (flag == "--pose-noise-deg") {
      noise_deg = std::stod(value);
    } else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  try {
    // The file as findmugd reads it; this tool uses the segmenter's and the maps' sections.
    Config config;
    daemon::DaemonConfig daemon_settings;
    const SettingsSchema schema = daemon::daemonSchema(config, daemon_settings);
    schema.readFile(config_path);
    schema.validate(config_path);
    config.segmenter.forest.num_threads = 1;
    const SemanticMapConfig map_config = daemon_settings.semantic_map_config;
    const TableMapConfig table_map_config = daemon_settings.table_map;
    auto forest = std::make_shared<const RandomForest>(RandomForest::load(model_path));
    const Segmenter segmenter(config.segmenter, forest);
    GroundTracker ground;  // the walk is one stream from one camera
    const double safety = config.segmenter.tables.safety_distance_m;
    std::string growth_rows, frame_rows, move_rows;
    std::printf("model %s, %d frames at %.1f fps per walk, pose noise %.3f m / %.2f deg%s\n\n",
                model_path.c_str(), frames, fps, noise_m, noise_deg,
                move_table >= 0 ? ", a table moved half-way" : "");
    std::printf(
        "Tables: P, R, mean centre error m, mean search-position error m (against the room as it "
        "is at the end).\n\n"
        "| seed | tables | labelled px | frame acc | fused acc (causal) | fused acc (final) | "
        "table map: P, R, centre err, search err | fused map: P, R, centre err, search err | "
        "fused tables frames (viewpoints) | integrate ms/frame (median) | tables() ms | voxels | "
        "memory MB | message kB |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (std::uint64_t seed : seeds) {
      const synth::SynthScene scene_before = synth::makeApartment(seed);
      synth::SynthScene scene_after = scene_before;
      int moved = -1;
      Eigen::Vector2d offset = Eigen::Vector2d::Zero();
      if (move_table >= 0) {
        // Table K, or the next one (cyclically) that has a free spot to go to.
        const int n = static_cast<int>(scene_before.tables.size());
        std::optional<Eigen::Vector2d> spot;
        for (int k = 0; k < n && !spot; ++k) {
          moved = (move_table + k) % n;
          spot = synth::freeSpotForTable(scene_before, moved);
        }
        if (!spot) {
          std::printf("| %llu | no free spot to move any table to: seed skipped |\n",
                      static_cast<unsigned long long>(seed));
          continue;
        }
        offset = *spot;
        synth::moveTable(scene_after, moved, offset);
      }
      // The path: one walk, or two halves, the second planned in the changed room.
      const int half = moved >= 0 ? frames / 2 : frames;
      std::vector<synth::CameraPose> path = synth::cameraPath(scene_before, half, fps);
      if (moved >= 0) {
        // The robot also comes back to look where the table stood: the second half is
        // planned with a stand-in for the old table (its truth only: nothing is rendered
        // there, and it blocks nothing).
        synth::SynthScene plan = scene_after;
        synth::TableTruth old_place = scene_before.tables[static_cast<std::size_t>(moved)];
        old_place.id = static_cast<int>(plan.tables.size());
        if (revisit) plan.tables.push_back(old_place);
        for (synth::CameraPose pose : synth::cameraPath(plan, frames - half, fps)) {
          pose.time_s += half / fps;
          path.push_back(pose);
        }
      }
      auto sceneAt = [&](std::size_t i) -> const synth::SynthScene& {
        return static_cast<int>(i) < half ? scene_before : scene_after;
      };
      std::mt19937_64 rng(seed * 7919);
      std::normal_distribution<double> gauss(0.0, 1.0);
      SemanticMap map(map_config, config.segmenter.tables);
      TableMap table_map(table_map_config, config.segmenter.tables);
      Accuracy frame_acc, causal_acc, final_acc;
      std::vector<double> integrate_ms;
      struct Kept {
        OrganizedCloud cloud;
        LabelImage labels;
        std::vector<std::uint8_t> truth;
        Eigen::Isometry3d camera;
        bool before_move = false;
      };
      std::vector<Kept> kept;
      std::string growth;
      Accuracy quarter_frame, quarter_fused;
      TableScore frame_tables_all, frame_tables_quarter;
      MoveEvents fused_events, map_events;
      const std::size_t quarter = std::max<std::size_t>(1, path.size() / 4);
      for (std::size_t i = 0; i < path.size(); ++i) {
        const synth::SynthScene& scene = sceneAt(i);
        synth::RenderedFrame rendered =
            synth::render(scene, path[i], synth::RenderOptions{}, seed * 100000 + i);
        rendered.labeled.frame.utime = static_cast<std::uint64_t>(path[i].time_s * 1e6) + 1;
        rendered.labeled.frame.seq = static_cast<std::int64_t>(i);
        // The tables the frame shows (1 % of its pixels), for the per-frame recall.
        std::vector<const synth::TableTruth*> visible;
        for (const synth::TableTruth& t : scene.tables) {
          const auto pixels = std::count(rendered.object.begin(), rendered.object.end(), t.object);
          if (pixels * 100 >= static_cast<long>(rendered.object.size())) visible.push_back(&t);
        }
        if (moved >= 0 && static_cast<int>(i) >= half &&
            placeInView(scene_before.tables[static_cast<std::size_t>(moved)], path[i],
                        rendered.labeled.frame.intrinsics, rendered.labeled.frame.width,
                        rendered.labeled.frame.height, map_config.max_range_m)) {
          ++fused_events.old_in_view;
        }
        LabelledFrame labelled = segmenter.process(std::move(rendered.labeled.frame), ground);
        const PreparedFrame& prepared = labelled.segmented.prepared;
        if (!prepared.ground) continue;
        Pose2D pose{path[i].xy.x(), path[i].xy.y(), path[i].yaw};
        pose.x += noise_m * gauss(rng);
        pose.y += noise_m * gauss(rng);
        pose.yaw += noise_deg * M_PI / 180.0 * gauss(rng);
        const Eigen::Isometry3d camera = cameraInMap(pose, prepared.ground->camera_to_ground);
        const double t0 = threadCpuMs();
        map.integrate(prepared.cloud_camera, labelled.labels, camera, prepared.frame.utime);
        integrate_ms.push_back(threadCpuMs() - t0);
        table_map.update(labelled.tables, pose, prepared.frame.utime);
        std::vector<TableCluster> in_map;
        for (const TableCluster& t : labelled.tables) in_map.push_back(transformTable(t, pose));
        const TableScore this_frame = score(in_map, visible, safety);
        frame_tables_all.add(this_frame);
        frame_tables_quarter.add(this_frame);
        const std::vector<std::uint8_t>& truth = rendered.labeled.labels;
        frame_acc.add(labelled.labels, truth);
        const LabelImage fused_labels =
            map.projectLabels(prepared.cloud_camera, labelled.labels, camera);
        causal_acc.add(fused_labels, truth);
        kept.push_back({prepared.cloud_camera, labelled.labels, truth, camera,
                        static_cast<int>(i) < half});
        quarter_frame.add(labelled.labels, truth);
        quarter_fused.add(fused_labels, truth);
        const bool quarter_end = (i + 1) % quarter == 0 || i + 1 == path.size();
        if (moved >= 0 && static_cast<int>(i) >= half) {
          const int since = static_cast<int>(i) - half + 1;
          const synth::TableTruth& before = scene_before.tables[static_cast<std::size_t>(moved)];
          const synth::TableTruth& after = scene_after.tables[static_cast<std::size_t>(moved)];
          fused_events.update(fusedClusters(map), before, after, since);
          map_events.update(table_map.confirmedTables(), before, after, since);
        }
        if (quarter_end) {
          char row[384];
          std::snprintf(row, sizeof(row), "| %llu | %zu | %.3f | %.3f | %s | %s | %s |\n",
                        static_cast<unsigned long long>(seed), i + 1, quarter_frame.value(),
                        quarter_fused.value(), pr(frame_tables_quarter).c_str(),
                        pr(score(table_map.confirmedTables(), scene, safety)).c_str(),
                        pr(score(fusedClusters(map), scene, safety)).c_str());
          growth += row;
          quarter_frame = Accuracy{};
          quarter_fused = Accuracy{};
          frame_tables_quarter = TableScore{};
        }
      }
      const synth::SynthScene& scene = scene_after;  // the room at the end
      for (const Kept& k : kept) {
        // The final map against frames from before the move: the moved table is where it
        // was then, so the final map is scored on the frames of the room it holds.
        if (moved >= 0 && k.before_move) continue;
        final_acc.add(map.projectLabels(k.cloud, k.labels, k.camera), k.truth);
      }
      const double t0 = threadCpuMs();
      const std::vector<FusedTable> fused = map.tables();
      const double tables_ms = threadCpuMs() - t0;
      std::vector<TableCluster> fused_tables;
      std::string support;
      for (const FusedTable& t : fused) {
        fused_tables.push_back(t.table);
        char entry[32];
        std::snprintf(entry, sizeof(entry), "%s%d (%d)", support.empty() ? "" : ", ", t.frames,
                      t.viewpoints);
        support += entry;
      }
      const std::vector<TableCluster> map_tables = table_map.confirmedTables();
      if (verbose) {
        if (moved >= 0) {
          std::fprintf(stderr, "seed %llu: table %d moved by (%.2f, %.2f) after frame %d\n",
                       static_cast<unsigned long long>(seed), moved, offset.x(), offset.y(), half);
        }
        for (const synth::TableTruth& t : scene.tables) {
          std::fprintf(stderr, "seed %llu truth %d %s: (%.2f, %.2f) %.2f x %.2f m, h %.2f\n",
                       static_cast<unsigned long long>(seed), t.id, t.kind.c_str(),
                       t.center_xy.x(), t.center_xy.y(), t.size.x(), t.size.y(), t.height);
        }
        for (const FusedTable& f : fused) {
          std::fprintf(stderr, "seed %llu fused %d: (%.2f, %.2f) %.2f x %.2f m, h %.2f, %d voxels\n",
                       static_cast<unsigned long long>(seed), f.table.id, f.table.center.x(),
                       f.table.center.y(), 2 * f.table.extents.x(), 2 * f.table.extents.y(),
                       f.table.top_height, f.voxels);
        }
        for (const TableCluster& t : map_tables) {
          std::fprintf(stderr, "seed %llu table map %d: (%.2f, %.2f) %.2f x %.2f m, h %.2f\n",
                       static_cast<unsigned long long>(seed), t.id, t.center.x(), t.center.y(),
                       2 * t.extents.x(), 2 * t.extents.y(), t.top_height);
        }
      }
      const auto message = io::encodeSemanticMap(io::semanticMapMessage(map, 0, 0));
      const SemanticMapStats stats = map.stats();
      std::printf("| %llu | %zu | %ld | %.3f | %.3f | %.3f | %s | %s | %s | %.1f | %.1f | %zu | "
                  "%.1f | %.1f |\n",
                  static_cast<unsigned long long>(seed), scene.tables.size(), frame_acc.total,
                  frame_acc.value(), causal_acc.value(), final_acc.value(),
                  pr(score(map_tables, scene, safety)).c_str(),
                  pr(score(fused_tables, scene, safety)).c_str(), support.c_str(),
                  median(integrate_ms), tables_ms, stats.voxels,
                  static_cast<double>(stats.memory_bytes) / (1 << 20),
                  static_cast<double>(message.data.size()) / 1024.0);
      std::fflush(stdout);
      growth_rows += growth;
      char row[256];
      std::snprintf(row, sizeof(row), "| %llu | %s |\n", static_cast<unsigned long long>(seed),
                    pr(frame_tables_all).c_str());
      frame_rows += row;
      if (moved >= 0) {
        const synth::TableTruth& before = scene_before.tables[static_cast<std::size_t>(moved)];
        const synth::TableTruth& after = scene_after.tables[static_cast<std::size_t>(moved)];
        char head[160];
        std::snprintf(head, sizeof(head), "| %llu | %d %s, %.2f m | %d | %d | ",
                      static_cast<unsigned long long>(seed), moved, before.kind.c_str(),
                      offset.norm(), frames - half, fused_events.old_in_view);
        move_rows += head +
                     fused_events.text(!anyOn(fused_tables, before), anyOn(fused_tables, after)) +
                     " | " +
                     map_events.text(!anyOn(map_tables, before), anyOn(map_tables, after)) +
                     " |\n";
      }
    }
    std::printf("\nEach frame's own tables, moved into the map by the frame's pose, against the "
                "tables the frame shows (all frames of the walk):\n\n"
                "| seed | per-frame tables: P, R, centre err, search err |\n|---|---|\n%s",
                frame_rows.c_str());
    if (move_table >= 0) {
      std::printf("\nThe moved table: frames after the move until the old place held no table "
                  "and until the new place held one (\"never\": not within the walk):\n\n"
                  "| seed | table moved, distance | frames after the move | of them seeing the "
                  "old place | fused map: old gone | fused map: new found | table map: old gone "
                  "| table map: new found |\n|---|---|---|---|---|---|---|---|\n%s",
                  move_rows.c_str());
    }
    std::printf("\n| seed | frames seen | frame acc (this quarter) | fused acc causal (this quarter) "
                "| per-frame tables (this quarter): P, R, centre err, search err "
                "| table map: P, R, centre err, search err | fused map: P, R, centre err, search "
                "err |\n|---|---|---|---|---|---|---|\n%s",
                growth_rows.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semantic_map_walk: %s\n", e.what());
    return 1;
  }
  return 0;
}
