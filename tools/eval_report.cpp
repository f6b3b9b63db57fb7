#include "eval_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/offline/training.hpp"
#include "findmug_json.hpp"

namespace findmug::tools {

namespace {

// Precisions at which the table precision/recall curve's operating point
// (highest recall) is reported: issue 10's target, and a looser one.
constexpr double kOperatingPrecisions[] = {0.8, 0.5};

// Wolf et al. 2014, NYU Depth V2, 5-fold CV: per class (floor .. object),
// class average, global. The paper gives no figure for "unknown".
constexpr double kPaperPerClass[kNumLabels] = {NAN, 96.9, 75.0, 92.3, 59.7, 72.2, 58.4, 40.0};
constexpr double kPaperClassAverage = 71.7;
constexpr double kPaperGlobal = 77.2;

std::string percent(double x) {
  if (std::isnan(x)) return "   -  ";
  char buf[16];
  std::snprintf(buf, sizeof buf, "%6.1f", 100.0 * x);
  return buf;
}

// Figures with six decimals; a figure that could not be measured (NaN) is null.
std::string jsonNumber(double x) { return cli::jsonNumber(x, 6); }

using cli::jsonString;

std::string jsonMatrix(const ConfusionMatrix& m) {
  std::ostringstream out;
  const auto per_class = m.perClassAccuracy();
  out << "{\"class_average\": " << jsonNumber(m.classAverageAccuracy())
      << ", \"global\": " << jsonNumber(m.globalAccuracy()) << ", \"pixels\": " << m.total()
      << ", \"per_class\": {";
  for (int c = 0; c < kNumLabels; ++c) {
    out << (c ? ", " : "") << "\"" << kLabelNames[c] << "\": " << jsonNumber(per_class[c]);
  }
  out << "}, \"confusion\": [";
  for (int t = 0; t < kNumLabels; ++t) {
    out << (t ? ", " : "") << "[";
    for (int p = 0; p <= kNumLabels; ++p) out << (p ? ", " : "") << m.count(t, p);
    out << "]";
  }
  out << "]}";
  return out.str();
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw Error(path + ": cannot write");
  out << text;
}

// formatTable's parts, in the order they print.
// The data, protocol, dropped frames, folds and how each frame got its ground.
void textHeader(std::ostringstream& out, const EvalReport& r) {
  out << "findmug-eval: " << r.data << "\n"
      << "protocol: " << r.protocol << "; frames used " << r.frames_used << " of " << r.frames_total
      << "\n";
  for (const auto& d : r.dropped) out << "  dropped " << d << "\n";
  for (const auto& fold : r.folds) {
    std::vector<std::string> scenes;
    for (const auto& s : fold.test_scenes)
      if (std::find(scenes.begin(), scenes.end(), s) == scenes.end()) scenes.push_back(s);
    out << "  fold " << fold.fold << ": " << fold.test_frames.size() << " test frames in "
        << scenes.size() << " scene(s), trained on " << fold.train_frames << ":";
    for (const auto& name : fold.test_frames) out << " " << name;
    out << "\n";
  }
  if (!r.ground_methods.empty()) {
    // One line per way the ground was obtained, with the frames that got it.
    std::vector<std::pair<std::string, std::string>> groups;  // method, frames
    for (const auto& [frame, method] : r.ground_methods) {
      const std::string& frame_method = method;  // clang 14 cannot capture a structured binding
      auto it = std::find_if(groups.begin(), groups.end(),
                             [&](const auto& g) { return g.first == frame_method; });
      if (it == groups.end()) {
        groups.emplace_back(method, frame);
      } else {
        it->second += " " + frame;
      }
    }
    for (const auto& [method, frames] : groups) {
      out << "  ground " << method << ": " << frames << "\n";
    }
  }
}

// Per-class accuracy of the forest, with the MRF, the paper's and the oracle's.
void textAccuracies(std::ostringstream& out, const EvalReport& r) {
  out << "\n  class        forest   +MRF   paper  oracle\n";
  const auto f = r.forest.perClassAccuracy();
  const auto m = r.mrf.perClassAccuracy();
  const auto o = r.oracle.perClassAccuracy();
  for (int c = 1; c <= kNumLabels; ++c) {
    const int k = c % kNumLabels;  // unknown last, as a footnote class
    char line[96];
    std::snprintf(line, sizeof line, "  %-10s %s %s %s %s\n", std::string(kLabelNames[k]).c_str(),
                  percent(f[k]).c_str(), percent(m[k]).c_str(),
                  percent(kPaperPerClass[k] / 100.0).c_str(), percent(o[k]).c_str());
    out << line;
  }
  char line[160];
  std::snprintf(line, sizeof line, "  %-10s %s %s %s %s\n  %-10s %s %s %s %s\n", "class avg",
                percent(r.forest.classAverageAccuracy()).c_str(),
                percent(r.mrf.classAverageAccuracy()).c_str(),
                percent(kPaperClassAverage / 100).c_str(),
                percent(r.oracle.classAverageAccuracy()).c_str(), "global",
                percent(r.forest.globalAccuracy()).c_str(), percent(r.mrf.globalAccuracy()).c_str(),
                percent(kPaperGlobal / 100).c_str(), percent(r.oracle.globalAccuracy()).c_str());
  out << line;
  out << "  (oracle: every patch labelled with its majority true label)\n";
}

// Where each class's pixels go with the MRF: rows truth, columns prediction,
// row-normalised; the last column is pixels left without a label.
void textConfusion(std::ostringstream& out, const EvalReport& r) {
  char line[160];
  out << "\n  +MRF confusion, % of each true class (rows: truth, columns: predicted)\n  "
      << std::string(10, ' ');
  for (int p = 0; p < kNumLabels; ++p) {
    std::snprintf(line, sizeof line, " %7.7s", std::string(kLabelNames[p]).c_str());
    out << line;
  }
  out << "    none\n";
  for (int t = 0; t < kNumLabels; ++t) {
    const double row = static_cast<double>(r.mrf.rowTotal(t));
    std::snprintf(line, sizeof line, "  %-10s", std::string(kLabelNames[t]).c_str());
    out << line;
    for (int p = 0; p <= kNumLabels; ++p) {
      std::snprintf(line, sizeof line, " %7.1f",
                    row > 0 ? 100.0 * static_cast<double>(r.mrf.count(t, p)) / row : 0.0);
      out << line;
    }
    out << "\n";
  }
}

// Table instances: counts, precision and recall, operating points, errors.
void textTableInstances(std::ostringstream& out, const EvalReport& r) {
  char line[160];
  const TableMetrics& t = r.tables;
  std::snprintf(line, sizeof line,
                "\n  table instances (forest+MRF, IoU >= 0.5): %d in ground truth, %d detected, "
                "%d matched\n",
                t.truth(), t.detected(), t.matched());
  out << line;
  std::snprintf(line, sizeof line, "  %-10s %s\n  %-10s %s\n", "precision",
                percent(t.precision()).c_str(), "recall", percent(t.recall()).c_str());
  out << line;
  const auto curve = precisionRecallCurve(r.scored_tables, t.truth());
  for (double min_precision : kOperatingPrecisions) {
    const PrecisionRecallPoint* p = operatingPoint(curve, min_precision);
    if (p) {
      std::snprintf(line, sizeof line,
                    "  at precision >= %.0f %%: recall %s (%d of %d detected, confidence >= "
                    "%.3f)\n",
                    100 * min_precision, percent(p->recall).c_str(), p->matched, p->detected,
                    p->threshold);
    } else {
      std::snprintf(line, sizeof line, "  at precision >= %.0f %%: no threshold reaches it\n",
                    100 * min_precision);
    }
    out << line;
  }
  if (t.matched() > 0) {
    std::snprintf(line, sizeof line,
                  "  matched tables, median error: height %.1f cm, centroid %.1f cm, "
                  "axis %.1f deg\n",
                  100 * t.medianHeightError(), 100 * t.medianCentroidError(),
                  t.medianAxisErrorDeg());
    out << line;
  }
}

// Searchable tables (matched by top overlap) and false tables.
void textSearchable(std::ostringstream& out, const EvalReport& r) {
  char line[160];
  const SearchableMetrics& s = r.searchable;
  out << "\n  searchable tables (true top >= table_metrics.searchable_min_top_area_m2, matched "
         "by top overlap): "
      << s.searchable() << " true, " << s.matched() << " matched, " << s.detected() << " detected ("
      << s.detectedSmall() << " on smaller true tables)\n";
  std::snprintf(line, sizeof line, "  %-10s %s\n  %-10s %s\n", "precision",
                percent(s.precision()).c_str(), "recall", percent(s.recall()).c_str());
  out << line;
  std::snprintf(
      line, sizeof line, "  false tables (on no true table): %d, in %d of %d frames (%.1f %%)\n",
      s.falseTables(), s.framesWithFalseTable(), s.frames(), 100 * s.falseTableFrameShare());
  out << line;
}

// What table_objects.relabel changes.
void textRelabel(std::ostringstream& out, const EvalReport& r) {
  const auto& m = r.relabel;
  const auto before = m.without.perClassAccuracy(), after = m.with.perClassAccuracy();
  const auto t = static_cast<std::size_t>(Label::Table);
  const auto o = static_cast<std::size_t>(Label::Object);
  char text[512];
  std::snprintf(
      text, sizeof text,
      "\n  table-top candidates' table pixels labelled object (table_objects.relabel), "
      "%d frames, %d candidates, %llu pixels changed:\n"
      "  %-10s %s -> %s\n  %-10s %s -> %s\n  %-10s %s -> %s\n  %-10s %s -> %s\n",
      m.frames, m.candidates, static_cast<unsigned long long>(m.pixels_changed), "table",
      percent(before[t]).c_str(), percent(after[t]).c_str(), "object", percent(before[o]).c_str(),
      percent(after[o]).c_str(), "class avg", percent(m.without.classAverageAccuracy()).c_str(),
      percent(m.with.classAverageAccuracy()).c_str(), "global",
      percent(m.without.globalAccuracy()).c_str(), percent(m.with.globalAccuracy()).c_str());
  out << text;
}

// Which true NYU-40 classes the table-labelled pixels come from.
void textTableByNyu40(std::ostringstream& out, const EvalReport& r) {
  char line[160];
  const auto& t = r.table_by_nyu40;
  std::uint64_t table_pixels = 0;
  for (const std::uint64_t n : t.labelled_table) table_pixels += n;
  std::vector<int> order;
  for (int c = 1; c <= 40; ++c) {
    if (t.labelled_table[static_cast<std::size_t>(c)] > 0) order.push_back(c);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return t.labelled_table[static_cast<std::size_t>(a)] >
           t.labelled_table[static_cast<std::size_t>(b)];
  });
  out << "\n  pixels labelled table, by true NYU-40 class (" << t.frames
      << " frames with label40; share of the table-labelled pixels, share of the class "
         "labelled table):\n";
  for (std::size_t k = 0; k < std::min<std::size_t>(order.size(), 10); ++k) {
    const auto c = static_cast<std::size_t>(order[k]);
    std::snprintf(
        line, sizeof line, "  %-16s %s of table pixels, %s of its own\n", nyu40ClassName(order[k]),
        percent(static_cast<double>(t.labelled_table[c]) / static_cast<double>(table_pixels))
            .c_str(),
        percent(static_cast<double>(t.labelled_table[c]) / static_cast<double>(t.pixels[c]))
            .c_str());
    out << line;
  }
}

// Search positions against the true tables.
void textSearchPositions(std::ostringstream& out, const EvalReport& r) {
  char line[160];
  const SearchPositionMetrics& p = r.search;
  std::snprintf(line, sizeof line,
                "  search positions vs true tables: %d predicted, median error %.1f cm, "
                "%.1f deg\n",
                p.predicted(), 100 * p.medianPositionError(), p.medianYawErrorDeg());
  out << line;
  std::snprintf(line, sizeof line,
                "  reachable in the true scene: %s %% of all, %s %% of the %d flagged "
                "reachable\n",
                percent(p.reachableShare()).c_str(), percent(p.flaggedReachableShare()).c_str(),
                p.flaggedReachable());
  out << line;
}

// The trees and depth sweeps.
void textSweep(std::ostringstream& out, const EvalReport& r) {
  char line[160];
  out << "\n  sweep   trees depth   forest(avg/glob)   mrf(avg/glob)\n";
  for (const auto* points : {&r.sweep_trees, &r.sweep_depth}) {
    for (const auto& p : *points) {
      std::snprintf(line, sizeof line, "          %5d %5d   %s %s   %s %s\n", p.trees, p.depth,
                    percent(p.forest.classAverageAccuracy()).c_str(),
                    percent(p.forest.globalAccuracy()).c_str(),
                    percent(p.mrf.classAverageAccuracy()).c_str(),
                    percent(p.mrf.globalAccuracy()).c_str());
      out << line;
    }
  }
}

// formatJson's parts, in the order they print.
// The data, protocol, dropped frames and each frame's ground method.
void jsonHeader(std::ostringstream& out, const EvalReport& r) {
  out << "{\n  \"data\": " << jsonString(r.data) << ",\n  \"protocol\": " << jsonString(r.protocol)
      << ",\n  \"frames_total\": " << r.frames_total << ",\n  \"frames_used\": " << r.frames_used
      << ",\n  \"dropped\": [";
  for (std::size_t i = 0; i < r.dropped.size(); ++i) {
    out << (i ? ", " : "") << jsonString(r.dropped[i]);
  }
  out << "],\n  \"ground\": [";
  for (std::size_t i = 0; i < r.ground_methods.size(); ++i) {
    out << (i ? ",\n    " : "\n    ") << "{\"frame\": " << jsonString(r.ground_methods[i].first)
        << ", \"method\": " << jsonString(r.ground_methods[i].second) << "}";
  }
}

// The fold rule and each fold's test and training frames (and pseudo-label rounds).
void jsonFolds(std::ostringstream& out, const EvalReport& r) {
  out << "],\n  \"folds\": {\"rule\": " << jsonString(r.fold_rule)
      << ", \"nyu_scenes\": " << jsonString(r.scene_rule) << ", \"folds\": [";
  for (std::size_t i = 0; i < r.folds.size(); ++i) {
    const auto& f = r.folds[i];
    out << (i ? ",\n    " : "\n    ") << "{\"fold\": " << f.fold
        << ", \"train_frames\": " << f.train_frames << ", \"test\": [";
    for (std::size_t k = 0; k < f.test_frames.size(); ++k) {
      out << (k ? ", " : "") << "{\"frame\": " << jsonString(f.test_frames[k])
          << ", \"scene\": " << jsonString(f.test_scenes[k]) << "}";
    }
    out << "], \"train\": [";
    for (std::size_t k = 0; k < f.train_frame_names.size(); ++k) {
      out << (k ? ", " : "") << jsonString(f.train_frame_names[k]);
    }
    out << "]";
    if (!f.pseudo_pool.empty()) {
      out << ", \"pseudo_pool\": [";
      for (std::size_t k = 0; k < f.pseudo_pool.size(); ++k)
        out << (k ? ", " : "") << jsonString(f.pseudo_pool[k]);
      out << "], \"pseudo_rounds\": [";
      for (std::size_t k = 0; k < f.pseudo_frames.size(); ++k) {
        out << (k ? ", " : "") << "{\"round\": " << k + 1
            << ", \"patches\": " << f.pseudo_patches[k] << ", \"frames\": [";
        for (std::size_t j = 0; j < f.pseudo_frames[k].size(); ++j)
          out << (j ? ", " : "") << jsonString(f.pseudo_frames[k][j]);
        out << "]}";
      }
      out << "]";
    }
    out << "}";
  }
  out << "]}";
}

// Self-training: each pseudo-label round's accuracy, and the unlabelled frames' ground.
void jsonPseudoRounds(std::ostringstream& out, const EvalReport& r) {
  out << ",\n  \"pseudo_rounds\": [";
  for (std::size_t i = 0; i < r.pseudo_rounds.size(); ++i) {
    const auto& p = r.pseudo_rounds[i];
    const auto acc = p.mrf.perClassAccuracy();
    out << (i ? ",\n    " : "\n    ") << "{\"round\": " << p.round
        << ", \"class_average\": " << jsonNumber(p.mrf.classAverageAccuracy())
        << ", \"global\": " << jsonNumber(p.mrf.globalAccuracy()) << ", \"per_class\": {";
    for (int c = 0; c < kNumLabels; ++c)
      out << (c ? ", " : "") << "\"" << kLabelNames[c] << "\": " << jsonNumber(acc[c]);
    out << "}, \"table_instance_precision\": " << jsonNumber(p.tables.precision())
        << ", \"table_instance_recall\": " << jsonNumber(p.tables.recall())
        << ", \"searchable_precision\": " << jsonNumber(p.searchable.precision())
        << ", \"searchable_recall\": " << jsonNumber(p.searchable.recall())
        << ", \"false_table_frame_share\": " << jsonNumber(p.searchable.falseTableFrameShare())
        << "}";
  }
  out << "],\n  \"unlabelled_ground\": [";
  for (std::size_t i = 0; i < r.unlabelled_ground_methods.size(); ++i)
    out << (i ? ", " : "") << "{\"frame\": " << jsonString(r.unlabelled_ground_methods[i].first)
        << ", \"method\": " << jsonString(r.unlabelled_ground_methods[i].second) << "}";
  out << "]";
}

// Table instances with their precision/recall curve, operating points and frames.
void jsonTableInstances(std::ostringstream& out, const EvalReport& r) {
  const TableMetrics& t = r.tables;
  out << ",\n  \"table_instances\": {\"labels\": \"forest+mrf\", \"truth\": " << t.truth()
      << ", \"detected\": " << t.detected() << ", \"matched\": " << t.matched()
      << ", \"precision\": " << jsonNumber(t.precision())
      << ", \"recall\": " << jsonNumber(t.recall())
      << ", \"median_height_error_m\": " << jsonNumber(t.medianHeightError())
      << ", \"median_centroid_error_m\": " << jsonNumber(t.medianCentroidError())
      << ", \"median_axis_error_deg\": " << jsonNumber(t.medianAxisErrorDeg())
      << ", \"precision_recall\": [";
  const auto curve = precisionRecallCurve(r.scored_tables, t.truth());
  for (std::size_t i = 0; i < curve.size(); ++i) {
    const auto& p = curve[i];
    out << (i ? ", " : "") << "{\"min_confidence\": " << jsonNumber(p.threshold)
        << ", \"detected\": " << p.detected << ", \"matched\": " << p.matched
        << ", \"precision\": " << jsonNumber(p.precision)
        << ", \"recall\": " << jsonNumber(p.recall) << "}";
  }
  out << "], \"operating_points\": [";
  for (std::size_t i = 0; i < std::size(kOperatingPrecisions); ++i) {
    const PrecisionRecallPoint* p = operatingPoint(curve, kOperatingPrecisions[i]);
    out << (i ? ", " : "") << "{\"min_precision\": " << jsonNumber(kOperatingPrecisions[i]);
    if (p) {
      out << ", \"min_confidence\": " << jsonNumber(p->threshold)
          << ", \"detected\": " << p->detected << ", \"matched\": " << p->matched
          << ", \"precision\": " << jsonNumber(p->precision)
          << ", \"recall\": " << jsonNumber(p->recall);
    } else {
      out << ", \"recall\": null";
    }
    out << "}";
  }
  out << "], \"per_frame\": [";
  for (std::size_t i = 0; i < r.frame_tables.size(); ++i) {
    const auto& f = r.frame_tables[i];
    out << (i ? ",\n    " : "\n    ") << "{\"frame\": " << jsonString(f.frame)
        << ", \"truth\": " << f.truth << ", \"detected\": " << f.detected
        << ", \"matched\": " << f.matched << "}";
  }
  out << "]}";
}

// What table_objects.relabel changes.
void jsonRelabel(std::ostringstream& out, const EvalReport& r) {
  const auto& m = r.relabel;
  const auto t = static_cast<std::size_t>(Label::Table);
  const auto o = static_cast<std::size_t>(Label::Object);
  const auto before = m.without.perClassAccuracy(), after = m.with.perClassAccuracy();
  out << ",\n  \"table_objects_relabel\": {\"frames\": " << m.frames
      << ", \"candidates\": " << m.candidates << ", \"pixels_changed\": " << m.pixels_changed
      << ", \"table\": [" << jsonNumber(before[t]) << ", " << jsonNumber(after[t])
      << "], \"object\": [" << jsonNumber(before[o]) << ", " << jsonNumber(after[o])
      << "], \"class_average\": [" << jsonNumber(m.without.classAverageAccuracy()) << ", "
      << jsonNumber(m.with.classAverageAccuracy()) << "], \"global\": ["
      << jsonNumber(m.without.globalAccuracy()) << ", " << jsonNumber(m.with.globalAccuracy())
      << "]}";
}

// Which true NYU-40 classes the table-labelled pixels come from.
void jsonTableByNyu40(std::ostringstream& out, const EvalReport& r) {
  const auto& t = r.table_by_nyu40;
  out << ",\n  \"table_by_nyu40\": {\"frames\": " << t.frames << ", \"classes\": [";
  bool first = true;
  for (int c = 1; c <= 40; ++c) {
    const auto k = static_cast<std::size_t>(c);
    if (t.pixels[k] == 0) continue;
    out << (first ? "" : ", ") << "{\"class\": " << jsonString(nyu40ClassName(c))
        << ", \"pixels\": " << t.pixels[k] << ", \"labelled_table\": " << t.labelled_table[k]
        << "}";
    first = false;
  }
  out << "]}";
}

// Searchable tables and false tables.
void jsonSearchable(std::ostringstream& out, const EvalReport& r) {
  const SearchableMetrics& s = r.searchable;
  out << ",\n  \"searchable_tables\": {\"labels\": \"forest+mrf\", \"frames\": " << s.frames()
      << ", \"truth\": " << s.searchable() << ", \"matched\": " << s.matched()
      << ", \"detected\": " << s.detected()
      << ", \"detected_on_small_tables\": " << s.detectedSmall()
      << ", \"false_tables\": " << s.falseTables()
      << ", \"frames_with_false_table\": " << s.framesWithFalseTable()
      << ", \"precision\": " << jsonNumber(s.precision())
      << ", \"recall\": " << jsonNumber(s.recall())
      << ", \"false_table_frame_share\": " << jsonNumber(s.falseTableFrameShare()) << "}";
}

// Search positions against the true tables.
void jsonSearchPositions(std::ostringstream& out, const EvalReport& r) {
  const SearchPositionMetrics& p = r.search;
  out << ",\n  \"search_positions\": {\"predicted\": " << p.predicted()
      << ", \"reachable_in_truth\": " << p.reachableInTruth()
      << ", \"reachable_share\": " << jsonNumber(p.reachableShare())
      << ", \"flagged_reachable\": " << p.flaggedReachable()
      << ", \"flagged_reachable_share\": " << jsonNumber(p.flaggedReachableShare())
      << ", \"median_position_error_m\": " << jsonNumber(p.medianPositionError())
      << ", \"median_yaw_error_deg\": " << jsonNumber(p.medianYawErrorDeg()) << "}";
}

// The trees and depth sweeps.
void jsonSweeps(std::ostringstream& out, const EvalReport& r) {
  for (const auto& [name, points] :
       {std::pair{"sweep_trees", &r.sweep_trees}, std::pair{"sweep_depth", &r.sweep_depth}}) {
    out << ",\n  \"" << name << "\": [";
    for (std::size_t i = 0; i < points->size(); ++i) {
      const auto& p = (*points)[i];
      out << (i ? ",\n    " : "\n    ") << "{\"trees\": " << p.trees << ", \"depth\": " << p.depth
          << ", \"forest\": {\"class_average\": " << jsonNumber(p.forest.classAverageAccuracy())
          << ", \"global\": " << jsonNumber(p.forest.globalAccuracy())
          << "}, \"mrf\": {\"class_average\": " << jsonNumber(p.mrf.classAverageAccuracy())
          << ", \"global\": " << jsonNumber(p.mrf.globalAccuracy()) << "}}";
    }
    out << "]";
  }
}

}  // namespace

std::string formatTable(const EvalReport& r) {
  std::ostringstream out;
  textHeader(out, r);
  textAccuracies(out, r);
  textConfusion(out, r);
  textTableInstances(out, r);
  textSearchable(out, r);
  if (r.relabel.frames > 0) textRelabel(out, r);
  if (r.table_by_nyu40.frames > 0) textTableByNyu40(out, r);
  if (r.has_search_truth) textSearchPositions(out, r);
  if (!r.sweep_trees.empty()) textSweep(out, r);
  char line[160];
  std::snprintf(line, sizeof line, "\n  time %.1f s\n", r.seconds);
  out << line;
  return out.str();
}

std::string formatJson(const EvalReport& r) {
  std::ostringstream out;
  jsonHeader(out, r);
  jsonFolds(out, r);
  if (!r.pseudo_rounds.empty()) jsonPseudoRounds(out, r);
  out << ",\n  \"train_extra\": [";
  for (std::size_t i = 0; i < r.train_extra.size(); ++i) {
    out << (i ? ", " : "") << jsonString(r.train_extra[i]);
  }
  out << "],\n  \"labels\": [";
  for (int c = 0; c < kNumLabels; ++c) out << (c ? ", " : "") << "\"" << kLabelNames[c] << "\"";
  out << "],\n  \"forest\": " << jsonMatrix(r.forest) << ",\n  \"mrf\": " << jsonMatrix(r.mrf)
      << ",\n  \"oracle\": " << jsonMatrix(r.oracle);
  jsonTableInstances(out, r);
  if (r.relabel.frames > 0) jsonRelabel(out, r);
  if (r.table_by_nyu40.frames > 0) jsonTableByNyu40(out, r);
  jsonSearchable(out, r);
  if (r.has_search_truth) jsonSearchPositions(out, r);
  jsonSweeps(out, r);
  out << ",\n  \"config\": " << jsonString(r.config_yaml)
      << ",\n  \"seconds\": " << jsonNumber(r.seconds) << "\n}\n";
  return out.str();
}

void writeConfusionSvg(const std::string& path, const ConfusionMatrix& m,
                       const std::string& title) {
  constexpr int kCell = 56, kLeft = 90, kTop = 70;
  const int size = kLeft + kCell * kNumLabels + 20;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << size << "\" height=\""
      << kTop + kCell * kNumLabels + 30 << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << kLeft << "\" y=\"20\" font-size=\"14\">" << title << "</text>\n"
      << "<text x=\"" << kLeft << "\" y=\"40\">columns: predicted, rows: ground truth</text>\n";
  for (int c = 0; c < kNumLabels; ++c) {
    svg << "<text x=\"" << kLeft + c * kCell + kCell / 2 << "\" y=\"" << kTop - 6
        << "\" text-anchor=\"middle\">" << kLabelNames[c] << "</text>\n"
        << "<text x=\"" << kLeft - 6 << "\" y=\"" << kTop + c * kCell + kCell / 2 + 4
        << "\" text-anchor=\"end\">" << kLabelNames[c] << "</text>\n";
  }
  for (int t = 0; t < kNumLabels; ++t) {
    const double row = static_cast<double>(m.rowTotal(t));
    for (int p = 0; p < kNumLabels; ++p) {
      const double share = row > 0 ? m.count(t, p) / row : 0.0;
      const int shade = static_cast<int>(255 - 215 * share);
      svg << "<rect x=\"" << kLeft + p * kCell << "\" y=\"" << kTop + t * kCell << "\" width=\""
          << kCell << "\" height=\"" << kCell << "\" fill=\"rgb(" << shade << "," << shade
          << ",255)\" stroke=\"#999\"/>\n";
      if (row > 0) {
        char text[16];
        std::snprintf(text, sizeof text, "%.0f", 100 * share);
        svg << "<text x=\"" << kLeft + p * kCell + kCell / 2 << "\" y=\""
            << kTop + t * kCell + kCell / 2 + 4 << "\" text-anchor=\"middle\" fill=\""
            << (share > 0.5 ? "white" : "black") << "\">" << text << "</text>\n";
      }
    }
  }
  svg << "</svg>\n";
  writeFile(path, svg.str());
}

void writeSweepSvg(const std::string& path, const std::vector<SweepPoint>& points, bool by_trees) {
  constexpr int kW = 520, kH = 340, kLeft = 60, kRight = 150, kTop = 40, kBottom = 50;
  const double x_max = by_trees ? 16 : 16, x_min = by_trees ? 1 : 2;
  auto px = [&](double x) { return kLeft + (x - x_min) / (x_max - x_min) * (kW - kLeft - kRight); };
  auto py = [&](double acc) { return kTop + (1.0 - acc) * (kH - kTop - kBottom); };
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kW << "\" height=\"" << kH
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << kLeft << "\" y=\"22\" font-size=\"14\">Accuracy vs "
      << (by_trees ? "number of trees" : "maximum tree depth") << "</text>\n";
  for (int pct = 0; pct <= 100; pct += 20) {
    svg << "<line x1=\"" << kLeft << "\" x2=\"" << kW - kRight << "\" y1=\"" << py(pct / 100.0)
        << "\" y2=\"" << py(pct / 100.0) << "\" stroke=\"#ddd\"/>\n"
        << "<text x=\"" << kLeft - 6 << "\" y=\"" << py(pct / 100.0) + 4
        << "\" text-anchor=\"end\">" << pct << "%</text>\n";
  }
  for (const auto& p : points) {
    const int x = by_trees ? p.trees : p.depth;
    svg << "<text x=\"" << px(x) << "\" y=\"" << kH - kBottom + 16 << "\" text-anchor=\"middle\">"
        << x << "</text>\n";
  }
  svg << "<text x=\"" << (kLeft + kW - kRight) / 2 << "\" y=\"" << kH - 12
      << "\" text-anchor=\"middle\">" << (by_trees ? "trees" : "max depth") << "</text>\n";
  struct Series {
    const char* name;
    const char* color;
    const char* dash;
    double (*value)(const SweepPoint&);
  };
  const Series series[] = {
      {"forest class avg", "#1f77b4", "",
       [](const SweepPoint& p) { return p.forest.classAverageAccuracy(); }},
      {"forest global", "#1f77b4", "6,4",
       [](const SweepPoint& p) { return p.forest.globalAccuracy(); }},
      {"MRF class avg", "#d62728", "",
       [](const SweepPoint& p) { return p.mrf.classAverageAccuracy(); }},
      {"MRF global", "#d62728", "6,4", [](const SweepPoint& p) { return p.mrf.globalAccuracy(); }},
  };
  int legend_y = kTop + 10;
  for (const auto& s : series) {
    svg << "<polyline fill=\"none\" stroke=\"" << s.color << "\" stroke-width=\"2\""
        << (*s.dash ? std::string(" stroke-dasharray=\"") + s.dash + "\"" : std::string())
        << " points=\"";
    for (const auto& p : points) {
      const double v = s.value(p);
      if (!std::isnan(v)) svg << px(by_trees ? p.trees : p.depth) << "," << py(v) << " ";
    }
    svg << "\"/>\n<line x1=\"" << kW - kRight + 10 << "\" x2=\"" << kW - kRight + 34 << "\" y1=\""
        << legend_y << "\" y2=\"" << legend_y << "\" stroke=\"" << s.color
        << "\" stroke-width=\"2\""
        << (*s.dash ? std::string(" stroke-dasharray=\"") + s.dash + "\"" : std::string())
        << "/>\n<text x=\"" << kW - kRight + 38 << "\" y=\"" << legend_y + 4 << "\">" << s.name
        << "</text>\n";
    legend_y += 18;
  }
  svg << "</svg>\n";
  writeFile(path, svg.str());
}

}  // namespace findmug::tools
