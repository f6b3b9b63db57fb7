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
//   * the map stage's CPU per frame (integrate, thread CPU time, median), tables() CPU,
//     voxels and memory after the walk, and the map message's size (zlib);
//   * then, per quarter of each walk, how it grows: frame and causal fused accuracy over the
//     quarter's frames, and the tables of both maps against the truth at its end.
//
//   semantic_map_walk [--config daemon/findmugd.yaml] [--model models/findmug.fmf]
//                     [--seeds 1,2,3] [--frames 60] [--fps 2]
//                     [--pose-noise-m 0] [--pose-noise-deg 0] [--verbose 1]
// --verbose 1 also lists every true table and every table of both maps at the end (stderr).
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/pipeline/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/synth/synth.hpp"

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
};

// Map-frame table centres against the true tables: one to one, a centre on a true top.
TableScore score(const std::vector<Eigen::Vector2d>& centres, const synth::SynthScene& scene) {
  TableScore s;
  s.detected = static_cast<int>(centres.size());
  s.truth = static_cast<int>(scene.tables.size());
  std::vector<bool> used(centres.size(), false);
  for (const synth::TableTruth& t : scene.tables) {
    int best = -1;
    double best_d = 1e9;
    for (std::size_t k = 0; k < centres.size(); ++k) {
      if (used[k] || synth::signedDistanceToTop(t, centres[k]) >= 0.0) continue;
      const double d = (centres[k] - t.center_xy).norm();
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(k);
      }
    }
    if (best >= 0) {
      used[static_cast<std::size_t>(best)] = true;
      ++s.matched;
      s.error_sum += best_d;
    }
  }
  return s;
}

std::string pr(const TableScore& s) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "%d/%d, %d/%d, %.3f", s.matched, s.detected, s.matched, s.truth,
                s.matched ? s.error_sum / s.matched : 0.0);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  std::string config_path = "daemon/findmugd.yaml", model_path = "models/findmug.fmf";
  std::vector<std::uint64_t> seeds = {1, 2, 3};
  int frames = 60;
  double fps = 2.0, noise_m = 0.0, noise_deg = 0.0;
  bool verbose = false;
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
    // findmugd's own sections are kept unchecked (this tool links the core only).
    configSections().addSectionName("daemon");
    configSections().addSectionName("check");
    Config config = loadConfig(config_path);
    config.segmenter.forest.num_threads = 1;
    const SemanticMapConfig map_config = resolveSemanticMapConfig(config);
    const TableMapConfig table_map_config = resolveTableMapConfig(config);
    auto forest = std::make_shared<const RandomForest>(RandomForest::load(model_path));
    const Segmenter segmenter(config.segmenter, forest);
    std::string growth_rows;
    std::printf("model %s, %d frames at %.1f fps per walk, pose noise %.3f m / %.2f deg\n\n",
                model_path.c_str(), frames, fps, noise_m, noise_deg);
    std::printf(
        "| seed | tables | labelled px | frame acc | fused acc (causal) | fused acc (final) | "
        "table map: P, R, centre err m | fused map: P, R, centre err m | fused tables frames "
        "(viewpoints) | integrate ms/frame (median) | tables() ms | voxels | memory MB | "
        "message kB |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (std::uint64_t seed : seeds) {
      const synth::SynthScene scene = synth::makeApartment(seed);
      const std::vector<synth::CameraPose> path = synth::cameraPath(scene, frames, fps);
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
      };
      std::vector<Kept> kept;
      std::string growth;
      Accuracy quarter_frame, quarter_fused;
      const std::size_t quarter = std::max<std::size_t>(1, path.size() / 4);
      for (std::size_t i = 0; i < path.size(); ++i) {
        synth::RenderedFrame rendered =
            synth::render(scene, path[i], synth::RenderOptions{}, seed * 100000 + i);
        rendered.labeled.frame.utime = static_cast<std::uint64_t>(path[i].time_s * 1e6) + 1;
        rendered.labeled.frame.seq = static_cast<std::int64_t>(i);
        LabelledFrame labelled = segmenter.process(std::move(rendered.labeled.frame));
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
        const std::vector<std::uint8_t>& truth = rendered.labeled.labels;
        frame_acc.add(labelled.labels, truth);
        causal_acc.add(map.projectLabels(prepared.cloud_camera, labelled.labels, camera), truth);
        kept.push_back({prepared.cloud_camera, labelled.labels, truth, camera});
        quarter_frame.add(labelled.labels, truth);
        quarter_fused.add(map.projectLabels(prepared.cloud_camera, labelled.labels, camera), truth);
        if ((i + 1) % quarter == 0 || i + 1 == path.size()) {
          std::vector<Eigen::Vector2d> fused_now, map_now;
          for (const FusedTable& t : map.tables()) fused_now.push_back(t.table.center.cast<double>());
          for (const TableCluster& t : table_map.confirmedTables()) {
            map_now.push_back(t.center.cast<double>());
          }
          char row[256];
          std::snprintf(row, sizeof(row), "| %llu | %zu | %.3f | %.3f | %s | %s |\n",
                        static_cast<unsigned long long>(seed), i + 1, quarter_frame.value(),
                        quarter_fused.value(), pr(score(map_now, scene)).c_str(),
                        pr(score(fused_now, scene)).c_str());
          growth += row;
          quarter_frame = Accuracy{};
          quarter_fused = Accuracy{};
        }
      }
      for (const Kept& k : kept) final_acc.add(map.projectLabels(k.cloud, k.labels, k.camera), k.truth);
      const double t0 = threadCpuMs();
      const std::vector<FusedTable> fused = map.tables();
      const double tables_ms = threadCpuMs() - t0;
      std::vector<Eigen::Vector2d> fused_centres, map_centres;
      std::string support;
      for (const FusedTable& t : fused) {
        fused_centres.push_back(t.table.center.cast<double>());
        char entry[32];
        std::snprintf(entry, sizeof(entry), "%s%d (%d)", support.empty() ? "" : ", ", t.frames,
                      t.viewpoints);
        support += entry;
      }
      for (const TableCluster& t : table_map.confirmedTables()) {
        map_centres.push_back(t.center.cast<double>());
      }
      if (verbose) {
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
        for (const TableCluster& t : table_map.confirmedTables()) {
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
                  pr(score(map_centres, scene)).c_str(), pr(score(fused_centres, scene)).c_str(),
                  support.c_str(), median(integrate_ms), tables_ms, stats.voxels,
                  static_cast<double>(stats.memory_bytes) / (1 << 20),
                  static_cast<double>(message.data.size()) / 1024.0);
      std::fflush(stdout);
      growth_rows += growth;
    }
    std::printf("\n| seed | frames seen | frame acc (this quarter) | fused acc causal (this quarter) "
                "| table map: P, R, centre err m | fused map: P, R, centre err m |\n"
                "|---|---|---|---|---|---|\n%s",
                growth_rows.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semantic_map_walk: %s\n", e.what());
    return 1;
  }
  return 0;
}
