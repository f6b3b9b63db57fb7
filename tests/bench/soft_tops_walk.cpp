// soft_tops_walk — do beds and sofas become tables in the table map? Rendered multi-room
// apartments (synth::makeMultiRoomApartment: bedrooms have a bed, living rooms a sofa), each
// bed, sofa and table looked at from up to three sides (1.8 m from its centre, facing it,
// two frames a view), every frame labelled by a model and its tables merged into one
// TableMap per apartment at the true pose, as findmugd does. Run twice side by side on the
// same frames: the table-top test on (the settings as given) and off
// (tables.min_flat_share=0). Prints, per apartment and in total, how many beds, sofas and
// tables have a confirmed map table whose box centre lies on their footprint, and how many
// frames had a detection on a bed or sofa.
//
//   soft_tops_walk [--config daemon/findmugd.yaml] [--model models/findmug-apartments.fmf]
//                  [--seeds 1,2,3,4,5,6] [--set section.key=value]...
// Default model: the sim-domain model, as findmug-search-bench runs it (the demo's
// models/findmug-nyu-synth.fmf, which never saw a bed, is the other case). Default --set:
// their settings (learner.classes=labels, features.objects=false, mrf.pairwise=potts).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/map/table_map.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/synth/synth.hpp"
#include "findmug_cli.hpp"
#include "program_settings.hpp"

namespace {

using namespace findmug;

// A table's box centre, base frame, moved into the map by `pose`.
Eigen::Vector2d inMap(const TableCluster& t, const Pose2D& pose) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return {pose.x + c * t.center.x() - s * t.center.y(),
          pose.y + s * t.center.x() + c * t.center.y()};
}

struct Counts {
  int beds = 0, sofas = 0, tables = 0;                       // looked at
  int beds_mapped = 0, sofas_mapped = 0, tables_mapped = 0;  // with a confirmed map table on them
  int frames = 0, frames_on_soft = 0;  // frames, frames with a detection on one
  void add(const Counts& o) {
    beds += o.beds, sofas += o.sofas, tables += o.tables;
    beds_mapped += o.beds_mapped, sofas_mapped += o.sofas_mapped;
    tables_mapped += o.tables_mapped, frames += o.frames, frames_on_soft += o.frames_on_soft;
  }
  std::string row() const {
    char line[200];
    std::snprintf(line, sizeof line, "%d of %d | %d of %d | %d of %d | %d of %d", beds_mapped, beds,
                  sofas_mapped, sofas, tables_mapped, tables, frames_on_soft, frames);
    return line;
  }
};

// One variant of the pipeline: its segmenter and the apartment's table map.
struct Variant {
  std::unique_ptr<Segmenter> segmenter;
  TableConfig tables;
  GroundTracker ground;  // each variant sees the walk as its own stream
};

}  // namespace

int main(int argc, char** argv) {
  std::string config_path = "daemon/findmugd.yaml", model_path = "models/findmug-apartments.fmf";
  std::vector<std::uint64_t> seeds = {1, 2, 3, 4, 5, 6};
  std::vector<std::string> sets = {"learner.classes=labels", "features.objects=false",
                                   "mrf.pairwise=potts"};
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
    } else if (flag == "--set") {
      sets.push_back(value);
    } else {
      std::fprintf(stderr, "soft_tops_walk: unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  try {
    Config config;
    daemon::DaemonConfig daemon_settings;
    const SettingsSchema schema = daemon::daemonSchema(config, daemon_settings);
    schema.readFile(config_path);
    for (const std::string& s : sets) schema.applyOverride(s);
    schema.validate(config_path);
    config.segmenter.forest.num_threads = 1;
    auto forest = std::make_shared<const RandomForest>(RandomForest::load(model_path));
    SegmenterConfig off = config.segmenter;
    off.tables.min_flat_share = 0.0f;
    Variant variants[2] = {{std::make_unique<Segmenter>(config.segmenter, forest), {}, {}},
                           {std::make_unique<Segmenter>(off, forest), {}, {}}};
    variants[0].tables = config.segmenter.tables;
    variants[1].tables = off.tables;
    std::printf(
        "model %s; a cell: furniture with a confirmed map table on it, of those looked "
        "at; frames: with a detection on a bed or sofa\n\n",
        model_path.c_str());
    std::printf(
        "| apartment | test | beds | sofas | tables | frames |\n|---|---|---|---|---|---|\n");
    Counts total[2];
    for (const std::uint64_t seed : seeds) {
      const synth::MultiRoomApartment apt = synth::makeMultiRoomApartment(seed);
      const synth::SynthScene& scene = apt.scene;
      TableMap maps[2] = {TableMap(daemon_settings.table_map, variants[0].tables),
                          TableMap(daemon_settings.table_map, variants[1].tables)};
      Counts counts[2];
      std::vector<const synth::FurnitureTruth*> looked;
      double time_s = 0.0;
      int frame_index = 0;
      for (const synth::FurnitureTruth& f : apt.furniture) {
        if (f.kind != "bed" && f.kind != "sofa" && f.kind != "table") continue;
        const Eigen::Vector2d c = f.centre();
        int views = 0;
        for (int k = 0; k < 8 && views < 3; ++k) {
          const double a = k * M_PI / 4.0;
          const Eigen::Vector2d xy = c + 1.8 * Eigen::Vector2d(std::cos(a), std::sin(a));
          if (apt.roomAt(xy) != f.room ||
              !synth::robotFits(scene.room_size, scene.obstacles, xy, 0.3)) {
            continue;
          }
          ++views;
          synth::CameraPose pose;
          pose.xy = xy;
          pose.yaw = std::atan2(c.y() - xy.y(), c.x() - xy.x());
          for (int shot = 0; shot < 2; ++shot, time_s += 0.5, ++frame_index) {
            pose.time_s = time_s;
            for (int v = 0; v < 2; ++v) {
              synth::RenderedFrame rendered =
                  synth::render(scene, pose, synth::RenderOptions{}, seed * 100000 + frame_index);
              rendered.labeled.frame.utime = static_cast<std::uint64_t>(time_s * 1e6) + 1;
              rendered.labeled.frame.seq = frame_index;
              LabelledFrame labelled =
                  variants[v].segmenter->process(std::move(rendered.labeled.frame), variants[v].ground);
              if (!labelled.segmented.prepared.ground) continue;
              const Pose2D base{xy.x(), xy.y(), pose.yaw};
              ++counts[v].frames;
              bool on_soft = false;
              for (const TableCluster& t : labelled.tables) {
                for (const synth::FurnitureTruth& g : apt.furniture)
                  on_soft |= (g.kind == "bed" || g.kind == "sofa") &&
                             g.covers(inMap(t, base));
              }
              counts[v].frames_on_soft += on_soft;
              maps[v].update(labelled.tables, base, labelled.segmented.prepared.frame.utime);
            }
          }
        }
        if (views > 0) looked.push_back(&f);
      }
      for (int v = 0; v < 2; ++v) {
        const std::vector<TableCluster> confirmed = maps[v].confirmedTables();
        for (const synth::FurnitureTruth* f : looked) {
          bool mapped = false;
          for (const TableCluster& t : confirmed)
            mapped |= f->covers(t.center.cast<double>());
          if (f->kind == "bed") counts[v].beds += 1, counts[v].beds_mapped += mapped;
          if (f->kind == "sofa") counts[v].sofas += 1, counts[v].sofas_mapped += mapped;
          if (f->kind == "table") counts[v].tables += 1, counts[v].tables_mapped += mapped;
        }
        total[v].add(counts[v]);
        std::printf("| %llu | %s | %s |\n", static_cast<unsigned long long>(seed),
                    v == 0 ? "on" : "off", counts[v].row().c_str());
      }
      std::fflush(stdout);
    }
    for (int v = 0; v < 2; ++v)
      std::printf("| all | %s | %s |\n", v == 0 ? "on" : "off", total[v].row().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soft_tops_walk: %s\n", e.what());
    return 1;
  }
  return 0;
}
