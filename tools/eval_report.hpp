// findmug-eval's report: terminal table, JSON, and SVG pictures.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "findmug/metrics.hpp"
#include "findmug/table_metrics.hpp"
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
  // Every detection's score (mean label confidence) and whether it matched,
  // for the precision/recall curve over a score threshold.
  std::vector<ScoredDetection> scored_tables;
  // Why true instances and detections were not matched (eval_tables.hpp).
  TableDiagnosisCounts diagnosis;
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
// Accuracy against number of trees (`by_trees`) or against maximum depth.
void writeSweepSvg(const std::string& path, const std::vector<SweepPoint>& points, bool by_trees);

}  // namespace findmug::tools
