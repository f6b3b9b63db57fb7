// findmug-eval's report: terminal table, JSON, and SVG pictures.
#pragma once

#include <cstdint>
#include <filesystem>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "findmug/offline/metrics.hpp"
#include "findmug/offline/table_metrics.hpp"
#include "eval_tables.hpp"

namespace findmug::tools {

struct SweepPoint {
  int trees = 0;
  int depth = 0;
  ConfusionMatrix forest, mrf;
};

// Table instances of one evaluated frame (table_metrics.hpp).
struct FrameTables {
  std::string frame;
  int truth = 0, detected = 0, matched = 0;
};

struct EvalReport {
  std::string data;
  std::string protocol;
  // Cross-validation: how folds were formed ("scenes" or "blocks") and each
  // fold's test frames with their scenes (cv_folds.hpp).
  struct Fold {
    int fold = 0;
    int train_frames = 0;
    std::vector<std::string> test_frames, test_scenes, train_frame_names;
    // Semi-supervised rounds (--unlabelled): the unlabelled frames offered to
    // this fold, and per round the frames that gave patches and how many.
    std::vector<std::string> pseudo_pool;
    std::vector<std::vector<std::string>> pseudo_frames;
    std::vector<int> pseudo_patches;
  };
  // Semi-supervised rounds: the figures after each round (0 = labelled frames
  // only), every fold's model of that round on its test frames.
  struct PseudoRound {
    int round = 0;
    ConfusionMatrix mrf;
    SearchableMetrics searchable;
    TableMetrics tables;
  };
  std::vector<PseudoRound> pseudo_rounds;
  std::vector<std::pair<std::string, std::string>> unlabelled_ground_methods;
  std::string fold_rule;
  std::string scene_rule;  // how NYU frames' scenes were formed
  std::vector<Fold> folds;
  std::vector<std::string> train_extra;  // data sets added to every fold's training
  int frames_total = 0;
  int frames_used = 0;
  std::vector<std::string> dropped;
  // (frame, how its ground frame was obtained) for every used frame.
  std::vector<std::pair<std::string, std::string>> ground_methods;
  std::string config_yaml;
  ConfusionMatrix forest, mrf;
  // The oversegmentation's ceiling: every patch given its majority true label
  // (what a perfect patch classifier would score; void-majority patches count
  // as unlabelled).
  ConfusionMatrix oracle;
  // Tables detected on the forest+MRF labels against ground-truth instances.
  TableMetrics tables;
  std::vector<FrameTables> frame_tables;
  // Tables a robot can search (table_metrics.hpp: searchable P/R, false tables).
  SearchableMetrics searchable;
  // Every detection's score (mean label confidence) and whether it matched,
  // for the precision/recall curve over a score threshold.
  std::vector<ScoredDetection> scored_tables;
  // Why true instances and detections were not matched (eval_tables.hpp).
  TableDiagnosisCounts diagnosis;
  // The table-top object candidates (objects/table_objects.hpp) found on each frame's
  // detected tables, and the forest+MRF labels without and with their table pixels
  // labelled Object (table_objects.relabel), over the frames whose tables were measured:
  // what the relabelling does to the object and table classes, side by side in one run.
  struct Relabel {
    int frames = 0, candidates = 0;
    std::uint64_t pixels_changed = 0;
    ConfusionMatrix without, with;
  } relabel;
  // Where the forest+MRF labels say Table, the true NYU-40 class (the folders' label40/
  // images, where present): pixels of each class (index = NYU-40 id, 0 unlabelled) and of
  // those the ones labelled Table, over the evaluated frames. What becomes "table" (bed,
  // sofa, counter, dresser, ...) is what makes false tables.
  struct TableByNyu40 {
    int frames = 0;
    std::array<std::uint64_t, 41> pixels{}, labelled_table{};
  } table_by_nyu40;
  // Synthetic folders only: their search positions against the true tables'.
  bool has_search_truth = false;
  SearchPositionMetrics search;
  std::vector<SweepPoint> sweep_trees, sweep_depth;
  double seconds = 0;
};

std::string formatTable(const EvalReport& report);
// JSON with `forest`, `mrf` and `oracle` objects holding class_average, global,
// per_class (by label name) and the confusion matrix; plus the sweeps.
std::string formatJson(const EvalReport& report);
void writeConfusionSvg(const std::string& path, const ConfusionMatrix& matrix,
                       const std::string& title);
// One cross-validation of a learning curve (--learning-curve).
struct LearningCurvePoint {
  int requested = 0;          // training frames asked for per fold; 0 = all
  double train_frames = 0.0;  // mean over folds of the frames really used
  int seed = 0;
  std::uint64_t forest_seed = 0;
  double class_average = 0, global = 0, table_accuracy = 0, table_iou = 0;
  double instance_precision = 0, instance_recall = 0;
  double searchable_precision = 0, searchable_recall = 0, false_table_frame_share = 0;
  double seconds = 0;
};
// learning_curve.csv (one row per point), learning_curve_trend.csv (a + b ln N
// per figure) and learning_curve.svg (figures against N with their trends and
// formulas) in `dir`; `protocol` is written into the SVG's caption.
void writeLearningCurve(const std::filesystem::path& dir,
                        const std::vector<LearningCurvePoint>& points, const std::string& protocol);
// The fitted trends as text, one line per figure.
std::string formatLearningCurveTrends(const std::vector<LearningCurvePoint>& points);

// Accuracy against number of trees (`by_trees`) or against maximum depth.
void writeSweepSvg(const std::string& path, const std::vector<SweepPoint>& points, bool by_trees);

}  // namespace findmug::tools
