// findmug-eval's learning curve output (--learning-curve): CSV, trend fits, SVG.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "eval_report.hpp"
#include "findmug/common/error.hpp"
#include "findmug/offline/cv_folds.hpp"

namespace findmug::tools {
namespace {

struct Figure {
  const char* key;
  const char* name;
  const char* color;
  double LearningCurvePoint::*value;
};

constexpr Figure kFigures[] = {
    {"class_average", "class average", "#1f77b4", &LearningCurvePoint::class_average},
    {"global", "global", "#7f7f7f", &LearningCurvePoint::global},
    {"table_accuracy", "table accuracy", "#d62728", &LearningCurvePoint::table_accuracy},
    {"table_iou", "table IoU", "#ff7f0e", &LearningCurvePoint::table_iou},
    {"searchable_precision", "searchable P", "#2ca02c", &LearningCurvePoint::searchable_precision},
    {"searchable_recall", "searchable R", "#9467bd", &LearningCurvePoint::searchable_recall},
};

std::string csvNumber(double x) {
  if (std::isnan(x)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", x);
  return buf;
}

// The trend of one figure over all points, or nullopt-like `points == 0`
// when fewer than two distinct N have a value.
LogTrend trendOf(const std::vector<LearningCurvePoint>& points, double LearningCurvePoint::*value) {
  std::vector<double> x, y;
  for (const auto& p : points) {
    if (!(p.train_frames > 0)) continue;
    x.push_back(p.train_frames);
    y.push_back(p.*value);
  }
  try {
    return fitLogTrend(x, y);
  } catch (const Error&) {
    return LogTrend{};
  }
}

std::string formula(const LogTrend& t) {
  if (t.points == 0) return "no trend (fewer than two sizes)";
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.1f %c %.1f ln N (R2 %.2f)", 100 * t.a, t.b < 0 ? '-' : '+',
                100 * std::abs(t.b), t.r2);
  return buf;
}

void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw Error(path.string() + ": cannot write");
  out << text;
}

}  // namespace

std::string formatLearningCurveTrends(const std::vector<LearningCurvePoint>& points) {
  std::ostringstream out;
  out << "learning curve trends (percent, N = training frames per fold):\n";
  for (const Figure& f : kFigures) {
    char line[160];
    std::snprintf(line, sizeof line, "  %-15s %s\n", f.name, formula(trendOf(points, f.value)).c_str());
    out << line;
  }
  return out.str();
}

void writeLearningCurve(const std::filesystem::path& dir,
                        const std::vector<LearningCurvePoint>& points,
                        const std::string& protocol) {
  std::ostringstream csv;
  csv << "train_frames_requested,train_frames_mean,seed,forest_seed,class_average,global,"
         "table_accuracy,table_iou,instance_precision,instance_recall,searchable_precision,"
         "searchable_recall,false_table_frame_share,seconds\n";
  for (const auto& p : points) {
    csv << (p.requested ? std::to_string(p.requested) : "all") << "," << csvNumber(p.train_frames)
        << "," << p.seed << "," << p.forest_seed << "," << csvNumber(p.class_average) << ","
        << csvNumber(p.global) << "," << csvNumber(p.table_accuracy) << ","
        << csvNumber(p.table_iou) << "," << csvNumber(p.instance_precision) << ","
        << csvNumber(p.instance_recall) << "," << csvNumber(p.searchable_precision) << ","
        << csvNumber(p.searchable_recall) << "," << csvNumber(p.false_table_frame_share) << ","
        << csvNumber(p.seconds) << "\n";
  }
  writeText(dir / "learning_curve.csv", csv.str());

  std::ostringstream trends;
  trends << "figure,a,b,r2,points\n";
  for (const Figure& f : kFigures) {
    const LogTrend t = trendOf(points, f.value);
    trends << f.key << "," << (t.points ? csvNumber(t.a) : "") << ","
           << (t.points ? csvNumber(t.b) : "") << "," << (t.points ? csvNumber(t.r2) : "") << ","
           << t.points << "\n";
  }
  writeText(dir / "learning_curve_trend.csv", trends.str());

  // Figures (0..100 %) against N on a logarithmic axis, where a + b ln N is a line.
  constexpr int kW = 760, kH = 460, kLeft = 60, kRight = 300, kTop = 50, kBottom = 70;
  double x_min = 1e9, x_max = 0;
  for (const auto& p : points) {
    if (!(p.train_frames > 0)) continue;
    x_min = std::min(x_min, p.train_frames);
    x_max = std::max(x_max, p.train_frames);
  }
  if (!(x_max > 0)) x_min = 1, x_max = 2;
  const double lo = std::log(x_min * 0.9), hi = std::log(x_max * 1.1);
  auto px = [&](double n) { return kLeft + (std::log(n) - lo) / (hi - lo) * (kW - kLeft - kRight); };
  auto py = [&](double v) { return kTop + (1.0 - v) * (kH - kTop - kBottom); };
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kW << "\" height=\"" << kH
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << kLeft << "\" y=\"22\" font-size=\"14\">Learning curve: forest+MRF "
      << "against training frames per fold (log scale), one dot per seed</text>\n";
  for (int pct = 0; pct <= 100; pct += 20) {
    svg << "<line x1=\"" << kLeft << "\" x2=\"" << kW - kRight << "\" y1=\"" << py(pct / 100.0)
        << "\" y2=\"" << py(pct / 100.0) << "\" stroke=\"#ddd\"/>\n<text x=\"" << kLeft - 6
        << "\" y=\"" << py(pct / 100.0) + 4 << "\" text-anchor=\"end\">" << pct << "%</text>\n";
  }
  for (int n : {2, 5, 10, 20, 30, 50, 100, 200}) {
    if (n < x_min * 0.9 || n > x_max * 1.1) continue;
    svg << "<line x1=\"" << px(n) << "\" x2=\"" << px(n) << "\" y1=\"" << kTop << "\" y2=\""
        << kH - kBottom << "\" stroke=\"#eee\"/>\n<text x=\"" << px(n) << "\" y=\""
        << kH - kBottom + 16 << "\" text-anchor=\"middle\">" << n << "</text>\n";
  }
  svg << "<text x=\"" << (kLeft + kW - kRight) / 2 << "\" y=\"" << kH - kBottom + 34
      << "\" text-anchor=\"middle\">N = training frames per fold (mean over folds)</text>\n";
  std::string caption = protocol;
  if (caption.size() > 120) caption = caption.substr(0, 117) + "...";
  svg << "<text x=\"" << kLeft << "\" y=\"" << kH - 10 << "\" font-size=\"10\" fill=\"#555\">"
      << caption << "</text>\n";
  int legend_y = kTop + 10;
  for (const Figure& f : kFigures) {
    for (const auto& p : points) {
      const double v = p.*f.value;
      if (std::isnan(v) || !(p.train_frames > 0)) continue;
      svg << "<circle cx=\"" << px(p.train_frames) << "\" cy=\"" << py(v)
          << "\" r=\"2.5\" fill=\"" << f.color << "\"/>\n";
    }
    const LogTrend t = trendOf(points, f.value);
    if (t.points) {
      svg << "<line x1=\"" << px(x_min) << "\" y1=\"" << py(t.at(x_min)) << "\" x2=\""
          << px(x_max) << "\" y2=\"" << py(t.at(x_max)) << "\" stroke=\"" << f.color
          << "\" stroke-width=\"2\"/>\n";
    }
    svg << "<line x1=\"" << kW - kRight + 10 << "\" x2=\"" << kW - kRight + 34 << "\" y1=\""
        << legend_y << "\" y2=\"" << legend_y << "\" stroke=\"" << f.color
        << "\" stroke-width=\"2\"/>\n<text x=\"" << kW - kRight + 38 << "\" y=\"" << legend_y + 4
        << "\">" << f.name << "</text>\n<text x=\"" << kW - kRight + 38 << "\" y=\""
        << legend_y + 18 << "\" font-size=\"11\" fill=\"#444\">" << formula(t) << "</text>\n";
    legend_y += 40;
  }
  svg << "</svg>\n";
  writeText(dir / "learning_curve.svg", svg.str());
}

}  // namespace findmug::tools
