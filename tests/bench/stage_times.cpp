// stage_times: wall time of each pipeline stage per 640x480 frame, median over
// a labelled dataset, for each oversegmenter side by side in one run, and for
// the organized oversegmenter with the region, scene and auto-context rounds.
//
//   stage_times [--data DIR] [--model MODEL] [--repeat N] [--clock wall|cpu]
//
// Without --model the forests are trained in-process on the same frames (the
// timing of prediction does not depend on what the trees learnt, only on
// their size); --model replaces the forest of the columns whose settings it
// matches (features.regions/scene/context, oversegmentation.method). Prints a Markdown table
// for BENCHMARKS.md. Single-threaded.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "test_data.hpp"

namespace {

using namespace findmug;

using bench::median;

struct Column {
  std::string name;
  std::map<std::string, std::vector<double>> stage_ms;
  std::vector<double> segments;
};

void record(Column& c, const StageTimings& t, std::size_t segments) {
  const std::pair<const char*, double> stages[] = {
      {"cloud", t.cloud_ms},       {"normals", t.normals_ms},   {"ground", t.ground_ms},
      {"oversegmentation", t.oversegmentation_ms}, {"features", t.features_ms},
      {"regions", t.regions_ms},   {"forest", t.forest_ms},     {"context", t.context_ms},
      {"mrf", t.mrf_ms},           {"labels", t.labels_ms},     {"tables", t.tables_ms},
      {"objects", t.objects_ms},   {"total", t.total()}};
  for (const auto& [name, ms] : stages) c.stage_ms[name].push_back(ms);
  c.segments.push_back(static_cast<double>(segments));
}

int run(int argc, char** argv) {
  std::string data = (test::dataRoot() / "nyuv2_labeled").string();
  std::string model_path;
  int repeat = 1;
  bool cpu_clock = false;  // --clock cpu: the calling thread's CPU time instead of wall time
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--clock")) {
      if (std::strcmp(argv[i + 1], "cpu") && std::strcmp(argv[i + 1], "wall"))
        throw Error(std::string("--clock: expected cpu or wall, got '") + argv[i + 1] + "'");
      cpu_clock = !std::strcmp(argv[i + 1], "cpu");
      continue;
    }
    if (!std::strcmp(argv[i], "--data")) data = argv[i + 1];
    else if (!std::strcmp(argv[i], "--model")) model_path = argv[i + 1];
    else if (!std::strcmp(argv[i], "--repeat")) repeat = bench::positiveCount("--repeat", argv[i + 1]);
    else throw Error(std::string("unknown flag ") + argv[i]);
  }
  const DatasetFolder dataset(data);
  std::vector<LabeledFrame> frames;
  for (std::size_t i = 0; i < dataset.size(); ++i) frames.push_back(dataset.load(i));

  SegmenterConfig base;
  base.ground.source = GroundSource::Estimated;  // what a robot without extrinsics does
  base.forest.num_threads = 1;

  SegmenterConfig contextual = base;
  contextual.oversegmentation.kind = OversegmenterKind::Organized;
  contextual.regions.enabled = true;
  contextual.context.enabled = true;
  struct Variant {
    std::string name;
    SegmenterConfig config;
    std::shared_ptr<const RandomForest> forest;
  };
  std::vector<Variant> variants;
  for (auto kind : {OversegmenterKind::PclSupervoxels, OversegmenterKind::Organized}) {
    SegmenterConfig config = base;
    config.oversegmentation.kind = kind;
    variants.push_back(
        {kind == OversegmenterKind::PclSupervoxels ? "PCL supervoxels" : "organized", config, {}});
  }
  variants.push_back({"organized + regions + context", contextual, {}});
  // The shipped model's configuration and the one before it (scene features
  // are timed in the `regions` row).
  SegmenterConfig regions = contextual;
  regions.context.enabled = false;
  variants.push_back({"organized + regions", regions, {}});
  SegmenterConfig scene = regions;
  scene.scene.enabled = true;
  variants.push_back({"organized + regions + scene", scene, {}});

  std::shared_ptr<const RandomForest> loaded;
  if (!model_path.empty()) loaded = std::make_shared<const RandomForest>(RandomForest::load(model_path));
  for (auto& v : variants) {
    if (loaded) {
      try {
        checkModelMatchesConfig(*loaded, v.config);
        v.forest = loaded;
        continue;
      } catch (const Error&) {
        // Not this column's model: train one below.
      }
    }
    SegmenterConfig train_config = v.config;
    train_config.oversegmentation.kind = OversegmenterKind::Organized;
    train_config.ground.source = GroundSource::FloorLabels;
    ExtractionReport report;
    const auto samples = extractSamples(dataset, Segmenter(train_config, nullptr), report);
    std::vector<const FrameSample*> all;
    for (const auto& s : samples) all.push_back(&s);
    v.forest = std::make_shared<const RandomForest>(trainModel(all, train_config));
  }

  std::vector<Column> columns;
  for (const auto& v : variants) {
    const Segmenter segmenter(v.config, v.forest);
    Column column;
    column.name = v.name + (v.forest == loaded ? " (--model)" : "");
    for (int r = 0; r < repeat; ++r) {
      for (const auto& f : frames) {
        const LabelledFrame out = segmenter.process(f.frame);
        if (!out.segmented.prepared.ground) continue;  // no plane: not a full pipeline run
        record(column, cpu_clock ? out.cpu_timings : out.timings,
               out.segmented.segmentation.segments.size());
      }
    }
    columns.push_back(std::move(column));
  }

  std::printf("Median %s time per stage (ms) over %zu frames x %d, %s, one thread, "
              "forest %zu trees\n\n",
              cpu_clock ? "CPU" : "wall", frames.size(), repeat, data.c_str(),
              variants.front().forest->trees().size());
  std::printf("| stage |");
  for (const auto& c : columns) std::printf(" %s |", c.name.c_str());
  std::printf("\n|---|");
  for (std::size_t i = 0; i < columns.size(); ++i) std::printf("---:|");
  std::printf("\n");
  for (const char* stage : {"cloud", "normals", "ground", "oversegmentation", "features", "regions",
                            "forest", "context", "mrf", "labels", "tables", "objects", "total"}) {
    std::printf("| %s |", stage);
    for (const auto& c : columns) std::printf(" %.1f |", median(c.stage_ms.at(stage)));
    std::printf("\n");
  }
  std::printf("| segments (median) |");
  for (const auto& c : columns) std::printf(" %.0f |", median(c.segments));
  std::printf("\n| frames timed |");
  for (const auto& c : columns) std::printf(" %zu |", c.segments.size());
  std::printf("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return findmug::bench::benchMain("stage_times", run, argc, argv); }
