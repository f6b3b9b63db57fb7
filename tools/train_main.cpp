// findmug-train: trains the randomized forest on a labelled dataset folder.
//
//   findmug-train --data DIR [--data DIR2 ...] --out MODEL [--unlabelled DIR ...]
//                 [--config FILE] [--set key=value ...]
//
// With --unlabelled and training.pseudo_rounds > 0 the model is retrained
// with pseudo-labelled patches of the unlabelled frames (pseudo_labels.hpp).
// Each --data folder is read with its own ground-truth labels; every
// patch with a non-void plurality label becomes one training sample.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/offline/pseudo_labels.hpp"
#include "findmug/offline/training.hpp"
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
  findmug::tools::DatasetFlags dataset;
  std::vector<std::string> unlabelled;
  std::string out;
  findmug::cli::ConfigFlags config;
};

int run(int argc, char** argv) {
  using namespace findmug;
  TrainFlags f;
  auto app = cli::makeApp("findmug-train", kDescription);
  tools::addDatasetFlags(*app, f.dataset);
  app->add_option("--out", f.out, "model file to write")
      ->required()
      ->type_name("MODEL")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  tools::addUnlabelledFlag(*app, f.unlabelled);
  cli::addConfigFlags(*app, f.config, "YAML config (segmenter settings)");
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  if (f.config.help_settings) {
    std::cout << cli::coreSettingsHelp();
    return 0;
  }
  if (f.dataset.data.empty() && f.dataset.mats.empty()) {
    std::cerr << "findmug-train: give at least one --data DIR or --mat FILE (see --help)\n";
    return 2;
  }
  const Config config = cli::configFrom(f.config);
  const Segmenter segmenter(config.segmenter, nullptr);
  const DatasetOptions options = tools::datasetOptions(f.dataset, config);
  const auto input = tools::LabeledInputs::open(f.dataset, options);

  const auto start = std::chrono::steady_clock::now();
  tools::ProgressBar bar_features("features " + input->frames().description);
  ExtractionReport report;
  std::vector<FrameSample> samples =
      extractTrainingSamples(input->frames(), segmenter, config.offline, report,
                             [&](int done, int total) { bar_features.update(done, total); });
  bar_features.finish();
  const int frames_total = report.frames_total;
  const std::vector<std::string>& dropped = report.dropped;
  const auto& ground_methods = report.ground_methods;
  if (samples.empty()) throw Error("no usable frame in the given --data/--mat inputs");

  std::vector<std::size_t> all(samples.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  const TrainingOptions& options_training = config.offline.training;
  const TrainingSet training =
      makeTrainingSet(samples, all, options_training.sample_weight, options_training.split_labels);
  if (training.labels.empty()) throw Error("no labelled patch to train on");

  ExtractionReport unlabelled_report;
  const std::vector<FrameSample> unlabelled = tools::extractUnlabelled(
      f.unlabelled, f.dataset, config.segmenter, *input, unlabelled_report);
  if (!f.unlabelled.empty() && options_training.pseudo_rounds == 0)
    std::cerr << "findmug-train: --unlabelled without training.pseudo_rounds > 0 does nothing\n";

  tools::ProgressBar bar("forests");
  std::vector<const FrameSample*> frames;
  for (const auto& s : samples) frames.push_back(&s);
  PseudoLabelReport pseudo;
  RandomForest forest = unlabelled.empty() || options_training.pseudo_rounds == 0
                            ? trainModel(frames, config.segmenter, options_training,
                                         [&](int done, int total) { bar.update(done, total); })
                            : trainModelWithPseudoLabels(frames, unlabelled, config.segmenter,
                                                         options_training, &pseudo);
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
  for (const auto& d : unlabelled_report.dropped)
    std::printf("  dropped          unlabelled %s\n", d.c_str());
  for (const auto& [name, method] : unlabelled_report.ground_methods)
    std::printf("  ground           %-12s %s (unlabelled)\n", name.c_str(), method.c_str());
  std::printf("  training patches %zu\n", training.labels.size());
  for (int c = 0; c < kNumLabels; ++c) {
    std::printf("    %-8s %7d\n", std::string(kLabelNames[c]).c_str(), per_class[c]);
  }
  if (!pseudo.rounds.empty()) {
    std::printf(
        "  pseudo-labelled  (training.pseudo_min_confidence %g, pseudo_weight %g, "
        "pseudo_class_cap %g)\n",
        options_training.pseudo_min_confidence, options_training.pseudo_weight,
        options_training.pseudo_class_cap);
    std::istringstream lines(formatPseudoLabelReport(pseudo));
    for (std::string line; std::getline(lines, line);) std::printf("    %s\n", line.c_str());
  }
  const auto& p = config.segmenter.forest;
  if (forest.learnerKind() == LearnerKind::XGBoost) {
    const auto& x = forest.xgboostParams();
    std::printf("  xgboost          %d rounds, max depth %d, eta %g, seed %d\n", x.rounds,
                x.max_depth, x.eta, x.seed);
  } else {
    std::printf("  forest           %d trees, max depth %d, seed %llu\n", p.num_trees, p.max_depth,
                static_cast<unsigned long long>(p.seed));
  }
  std::printf("  classes          %s (%d internal classes)\n",
              forest.internalClasses().scheme.c_str(), forest.internalClasses().count());
  std::printf("  features         %d columns%s%s%s%s\n", forest.dim(),
              config.segmenter.regions.enabled ? " (with region features)" : "",
              config.segmenter.scene.enabled ? " (with scene features)" : "",
              config.segmenter.objects.enabled ? " (with object features)" : "",
              forest.contextRound() ? ", auto-context round" : "");
  if (const PairwiseContext* term = forest.pairwiseContext())
    std::printf("  pairwise term    learned from %zu labelled neighbour pairs (mrf.pairwise = context)\n",
                term->training_edges);
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
