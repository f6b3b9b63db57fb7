// findmug-train: trains the randomized forest on a labelled dataset folder.
//
//   findmug-train --data DIR [--data DIR2 ...] --out MODEL [--config FILE] [--set key=value ...]
//
// Each --data folder is read with its own ground-truth labels; every
// supervoxel with a non-void plurality label becomes one training sample.
#include <chrono>
#include <cstdio>
#include <iostream>

#include "findmug/error.hpp"
#include "findmug/training.hpp"
#include "findmug_cli.hpp"
#include "tool_common.hpp"

namespace {

// Shown by --help above the flag list.
constexpr const char* kDescription =
    "Trains findmug's randomized forest on NYU-style dataset folders (rgb/, depth/ in mm,\n"
    "label8/ or label40/) or on the official NYU Depth V2 labelled .mat file, and writes a\n"
    "versioned model file. For the paper's protocol on NYU add --set ground.source=floor_labels;\n"
    "to use every NYU frame, --set ground.source=gravity --nyu-rotations FILE.";

struct TrainFlags {
  std::vector<std::string> data, mats;
  std::string out, nyu894_csv, nyu_rotations;
  bool no_nyu_border = false;
  findmug::cli::ConfigFlags config;
};

int run(int argc, char** argv) {
  using namespace findmug;
  TrainFlags f;
  auto app = cli::makeApp("findmug-train", kDescription);
  app->add_option("--data", f.data, "labelled dataset folder (repeatable)")
      ->type_name("DIR")
      ->allow_extra_args(false);
  app->add_option("--mat", f.mats, "the NYU Depth V2 labelled .mat file (repeatable)")
      ->type_name("FILE")
      ->allow_extra_args(false);
  app->add_option("--out", f.out, "model file to write")
      ->required()
      ->type_name("MODEL")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  cli::addConfigFlags(*app, f.config, "YAML config (segmenter settings)");
  app->add_option("--nyu894-csv", f.nyu894_csv,
                  "NYU 894-to-40 class map (CSV) for --mat (default: the installed one)")
      ->type_name("FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app->add_flag("--no-nyu-border", f.no_nyu_border,
                "keep the white border of NYU frames (masked as void by default)");
  app->add_option("--nyu-rotations", f.nyu_rotations,
                  "NYU's camera_rotations_NYU.txt: every NYU frame's gravity")
      ->type_name("FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  if (f.data.empty() && f.mats.empty()) {
    std::cerr << "findmug-train: give at least one --data DIR or --mat FILE (see --help)\n";
    return 2;
  }
  const Config config = cli::configFrom(f.config);
  const Segmenter segmenter(config.segmenter, nullptr);
  DatasetOptions options;
  options.mask_nyu_border = !f.no_nyu_border;
  // Split labels need each patch's finer class (label40/ or label13/ beside label8/).
  options.fine_labels_folder = fineLabelsFolder(config.segmenter.training.split_labels);
  if (config.segmenter.training.split_labels == SplitLabels::Nyu13 && !f.mats.empty())
    throw Error("training.split_labels = nyu13: --mat gives NYU-40 classes only (use nyu40, or a "
                "dataset folder with label13/)");
  if (!f.nyu_rotations.empty()) options.nyu_rotations_file = f.nyu_rotations;

  const auto start = std::chrono::steady_clock::now();
  std::vector<FrameSample> samples;
  int frames_total = 0;
  std::vector<std::string> dropped;
  std::vector<std::pair<std::string, std::string>> ground_methods;
  std::vector<std::unique_ptr<tools::LabeledInput>> inputs;
  for (const auto& dir : f.data) inputs.push_back(tools::LabeledInput::folder(dir, options));
  for (const auto& mat : f.mats) {
    inputs.push_back(tools::LabeledInput::mat(mat, f.nyu894_csv, options.nyu_rotations_file));
  }
  for (const auto& input : inputs) {
    tools::ProgressBar bar("features " + input->frames().description);
    ExtractionReport report;
    auto part = extractSamples(input->frames(), segmenter, report,
                               [&](int done, int total) { bar.update(done, total); });
    bar.finish();
    frames_total += report.frames_total;
    dropped.insert(dropped.end(), report.dropped.begin(), report.dropped.end());
    ground_methods.insert(ground_methods.end(), report.ground_methods.begin(),
                          report.ground_methods.end());
    for (auto& s : part) samples.push_back(std::move(s));
  }
  if (samples.empty()) throw Error("no usable frame in the given --data/--mat inputs");

  std::vector<std::size_t> all(samples.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  const TrainingSet training = makeTrainingSet(samples, all, config.segmenter.training.sample_weight,
                                               config.segmenter.training.split_labels);
  if (training.labels.empty()) throw Error("no labelled supervoxel to train on");

  tools::ProgressBar bar("forests");
  std::vector<const FrameSample*> frames;
  for (const auto& s : samples) frames.push_back(&s);
  RandomForest forest =
      trainModel(frames, config.segmenter, [&](int done, int total) { bar.update(done, total); });
  bar.finish();
  // Recorded so that the model is only ever run on features computed alike.
  forest.setExtractionSettings(extractionSettings(config.segmenter));
  forest.save(f.out);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::array<int, kNumLabels> per_class{};
  for (auto y : training.labels) ++per_class[y];
  std::printf("findmug-train summary\n");
  std::printf("  frames used      %zu of %d\n", samples.size(), frames_total);
  for (const auto& d : dropped) std::printf("  dropped          %s\n", d.c_str());
  for (const auto& [name, method] : ground_methods) {
    std::printf("  ground           %-12s %s\n", name.c_str(), method.c_str());
  }
  std::printf("  training patches %zu\n", training.labels.size());
  for (int c = 0; c < kNumLabels; ++c) {
    std::printf("    %-8s %7d\n", std::string(kLabelNames[c]).c_str(), per_class[c]);
  }
  const auto& p = config.segmenter.forest;
  std::printf("  forest           %d trees, max depth %d, seed %llu\n", p.num_trees, p.max_depth,
              static_cast<unsigned long long>(p.seed));
  std::printf("  features         %d columns%s%s%s%s\n", forest.dim(),
              config.segmenter.regions.enabled ? " (with region features)" : "",
              config.segmenter.scene.enabled ? " (with scene features)" : "",
              config.segmenter.objects.enabled ? " (with object features)" : "",
              forest.contextStage() ? ", auto-context stage" : "");
  std::printf("  model            %s (id %s)\n", f.out.c_str(), forest.id().c_str());
  std::printf("  time             %.1f s\n", seconds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "findmug-train: error: " << e.what() << "\n";
    return 1;
  }
}
