// findmug-eval's table diagnosis (see eval_tables.hpp).
#include "eval_tables.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "findmug/labels/labels.hpp"

namespace findmug::tools {
namespace {

// Normals within this angle of vertical count as horizontal surface.
constexpr float kHorizontalDeg = 20.0f;

// Label histogram of `labels` over the pixels of `mask` that are not in `except`.
std::array<int, kNumLabels + 1> histogram(const std::vector<std::uint8_t>& labels,
                                          const std::vector<int>& mask,
                                          const std::vector<int>* except = nullptr) {
  std::array<int, kNumLabels + 1> h{};  // last: void
  std::size_t j = 0;
  for (int p : mask) {
    if (except) {
      while (j < except->size() && (*except)[j] < p) ++j;
      if (j < except->size() && (*except)[j] == p) continue;
    }
    const std::uint8_t l = labels[static_cast<std::size_t>(p)];
    ++h[l < kNumLabels ? l : kNumLabels];
  }
  return h;
}

std::string nameOf(int label) {
  return label < kNumLabels ? std::string(kLabelNames[static_cast<std::size_t>(label)]) : "void";
}

// The most frequent label of a histogram, `skip` excluded (-1: none).
int dominant(const std::array<int, kNumLabels + 1>& h, int skip = -1) {
  int best = -1;
  for (int l = 0; l <= kNumLabels; ++l) {
    if (l == skip) continue;
    if (best < 0 || h[static_cast<std::size_t>(l)] > h[static_cast<std::size_t>(best)]) best = l;
  }
  return best;
}

std::string share(const std::array<int, kNumLabels + 1>& h) {
  int total = 0;
  for (int c : h) total += c;
  std::ostringstream out;
  bool first = true;
  for (int l = 0; l <= kNumLabels; ++l) {
    const int c = h[static_cast<std::size_t>(l)];
    if (total == 0 || c * 20 < total) continue;  // >= 5 %
    out << (first ? "" : " ") << nameOf(l) << " " << (100 * c + total / 2) / total << "%";
    first = false;
  }
  return out.str();
}

struct Summary {
  double p_table = std::nan("");
  double horizontal = std::nan("");
};

Summary summarize(const FrameTableEvidence& f, const TableCluster& t) {
  Summary s;
  if (f.table_probability && !t.pixels.empty()) {
    double sum = 0;
    for (int p : t.pixels) sum += (*f.table_probability)[static_cast<std::size_t>(p)];
    s.p_table = sum / static_cast<double>(t.pixels.size());
  }
  if (f.normals_ground && !t.pixels.empty()) {
    const float cos_max = std::cos(kHorizontalDeg * static_cast<float>(M_PI) / 180.0f);
    int valid = 0, horizontal = 0;
    for (int p : t.pixels) {
      const Eigen::Vector3f& n = f.normals_ground->normals[static_cast<std::size_t>(p)];
      if (!std::isfinite(n.z())) continue;
      ++valid;
      if (std::abs(n.z()) >= cos_max) ++horizontal;
    }
    if (valid > 0) s.horizontal = static_cast<double>(horizontal) / valid;
  }
  return s;
}

std::string describe(const FrameTableEvidence& f, const TableCluster& t) {
  const Summary s = summarize(f, t);
  int x0 = f.width, x1 = -1, y0 = f.height, y1 = -1;
  for (int p : t.pixels) {
    x0 = std::min(x0, p % f.width), x1 = std::max(x1, p % f.width);
    y0 = std::min(y0, p / f.width), y1 = std::max(y1, p / f.width);
  }
  // The border of the labelled area (NYU frames have a masked white border).
  int bx0 = f.width, bx1 = -1, by0 = f.height, by1 = -1;
  for (int p = 0; p < f.width * f.height; ++p) {
    if ((*f.truth_labels)[static_cast<std::size_t>(p)] == kVoidLabel) continue;
    bx0 = std::min(bx0, p % f.width), bx1 = std::max(bx1, p % f.width);
    by0 = std::min(by0, p / f.width), by1 = std::max(by1, p / f.width);
  }
  const bool border = x0 <= bx0 + 2 || y0 <= by0 + 2 || x1 >= bx1 - 2 || y1 >= by1 - 2;
  char line[320];
  std::snprintf(
      line, sizeof line,
      "%6d px, top %.2f m, box %.2f x %.2f m, top area %.2f m2, p(table) %.2f, confidence %.2f, "
      "horizontal %.0f%%, image box (%d,%d)-(%d,%d)%s",
      t.point_count, t.top_height, 2 * t.extents.x(), 2 * t.extents.y(), t.top_area_m2, s.p_table,
      t.mean_confidence, 100 * s.horizontal, x0, y0, x1, y1, border ? " at the image border" : "");
  return line;
}

}  // namespace

std::string diagnoseFrameTables(const FrameTableEvidence& f, const std::vector<TableCluster>& truth,
                                const std::vector<TableCluster>& detected,
                                const std::vector<TableMatch>& matches,
                                TableDiagnosisCounts& counts) {
  std::ostringstream out;
  out << "frame " << f.name << ": " << truth.size() << " true, " << detected.size() << " detected, "
      << matches.size() << " matched\n";
  std::vector<int> truth_match(truth.size(), -1), detected_match(detected.size(), -1);
  for (const auto& m : matches) {
    truth_match[static_cast<std::size_t>(m.truth)] = m.detected;
    detected_match[static_cast<std::size_t>(m.detected)] = m.truth;
  }
  std::vector<std::vector<int>> inter(truth.size(), std::vector<int>(detected.size(), 0));
  for (std::size_t t = 0; t < truth.size(); ++t) {
    for (std::size_t d = 0; d < detected.size(); ++d) {
      inter[t][d] = static_cast<int>(sortedIntersectionSize(truth[t].pixels, detected[d].pixels));
    }
  }
  auto iou = [&](std::size_t t, std::size_t d) {
    const int i = inter[t][d];
    return static_cast<double>(i) /
           static_cast<double>(truth[t].pixels.size() + detected[d].pixels.size() - i);
  };

  for (std::size_t t = 0; t < truth.size(); ++t) {
    const TableCluster& tc = truth[t];
    const int n = static_cast<int>(tc.pixels.size());
    std::string reason;
    if (truth_match[t] >= 0) {
      reason = "matched";
    } else {
      const auto predicted = histogram(*f.predicted_labels, tc.pixels);
      const int table_px = predicted[static_cast<std::size_t>(Label::Table)];
      std::vector<std::size_t> big;  // detections covering >= 10 % of the instance
      std::size_t best = detected.size();
      for (std::size_t d = 0; d < detected.size(); ++d) {
        if (inter[t][d] * 10 >= n) big.push_back(d);
        if (inter[t][d] > 0 && (best == detected.size() || iou(t, d) > iou(t, best))) best = d;
      }
      if (table_px * 4 < n) {
        reason = "labelled " + nameOf(dominant(predicted, static_cast<int>(Label::Table)));
      } else if (big.size() >= 2) {
        reason = "split";
      } else if (big.size() == 1) {
        const std::size_t d = big[0];
        const int outside = static_cast<int>(detected[d].pixels.size()) - inter[t][d];
        if (outside > inter[t][d] / 2 && inter[t][d] * 2 >= n) {
          const auto rest = histogram(*f.truth_labels, detected[d].pixels, &tc.pixels);
          reason = "merged with " + nameOf(dominant(rest));
        } else {
          reason = iou(t, d) >= 0.2 ? "partly covered (IoU 0.2-0.5)" : "partly covered (IoU < 0.2)";
        }
      } else {
        reason =
            "table-labelled but no detection (small cluster, out of height range, or "
            "dropped by tables.min_top_area_m2 / min_horizontal_share)";
      }
      (void)best;
    }
    ++counts.truth[reason];
    const auto predicted = histogram(*f.predicted_labels, tc.pixels);
    out << "  truth " << t << ": " << describe(f, tc)
        << "\n    predicted there: " << share(predicted) << "\n    -> " << reason << "\n";
  }
  for (std::size_t d = 0; d < detected.size(); ++d) {
    const TableCluster& dc = detected[d];
    const int n = static_cast<int>(dc.pixels.size());
    std::string reason;
    const auto truth_there = histogram(*f.truth_labels, dc.pixels);
    if (detected_match[d] >= 0) {
      reason = "matched";
    } else {
      std::size_t best = truth.size();
      for (std::size_t t = 0; t < truth.size(); ++t) {
        if (inter[t][d] > 0 && (best == truth.size() || inter[t][d] > inter[best][d])) best = t;
      }
      if (best < truth.size() && inter[best][d] * 10 >= 3 * n) {
        reason = truth_match[best] >= 0 ? "second piece of a matched true table"
                                        : "on a true table, IoU too low";
      } else if (dominant(truth_there) == static_cast<int>(Label::Table)) {
        reason = "on table pixels that are no instance (small or out of height)";
      } else {
        reason = "false positive on " + nameOf(dominant(truth_there));
      }
    }
    ++counts.detected[reason];
    out << "  detected " << d << ": " << describe(f, dc)
        << "\n    truth there: " << share(truth_there) << "\n    -> " << reason << "\n";
  }
  bool any = false;
  for (std::size_t t = 0; t < truth.size(); ++t) {
    for (std::size_t d = 0; d < detected.size(); ++d) {
      if (inter[t][d] == 0) continue;
      char cell[96];
      std::snprintf(cell, sizeof cell, "%s(t%zu,d%zu) %.2f", any ? "  " : "  IoU: ", t, d,
                    iou(t, d));
      out << cell;
      any = true;
    }
  }
  if (any) out << "\n";
  return out.str();
}

TableTopEvidence measureTableTop(const std::string& frame, const OrganizedCloud& cloud,
                                 const NormalImage& normals, const TableCluster& table,
                                 float top_band_m, const std::vector<std::uint8_t>* truth40) {
  TableTopEvidence e;
  e.frame = frame;
  e.points = table.point_count;
  e.top_height_m = table.top_height;
  e.length_m = 2.0 * table.extents.x();
  e.width_m = 2.0 * table.extents.y();
  e.top_area_m2 = table.top_area_m2;
  if (truth40) {
    std::array<int, 41> votes{};
    int labelled = 0;
    for (int p : table.pixels) {
      const std::uint8_t c = (*truth40)[static_cast<std::size_t>(p)];
      if (c == 0 || c > 40) continue;
      ++votes[c];
      ++labelled;
    }
    const auto best = std::max_element(votes.begin() + 1, votes.end());
    if (labelled > 0) {
      e.nyu40 = static_cast<int>(best - votes.begin());
      e.nyu40_share = static_cast<double>(*best) / labelled;
    }
  }
  double sum = 0, sum2 = 0;
  int band = 0, flat = 0;
  std::vector<float> tilts;
  for (int p : table.pixels) {
    const Eigen::Vector3f& q = cloud.points[static_cast<std::size_t>(p)];
    const float dz = q.z() - table.top_height;
    if (std::abs(dz) > top_band_m) continue;
    ++band;
    sum += dz;
    sum2 += static_cast<double>(dz) * dz;
    flat += std::abs(dz) <= 0.015f;
    const Eigen::Vector3f& n = normals.normals[static_cast<std::size_t>(p)];
    if (std::isfinite(n.z()))
      tilts.push_back(std::acos(std::min(1.0f, std::abs(n.z()))) * 180.0f /
                      static_cast<float>(M_PI));
  }
  if (band > 0) {
    const double mean = sum / band;
    e.band_spread_m = std::sqrt(std::max(0.0, sum2 / band - mean * mean));
    e.band_flat_share = static_cast<double>(flat) / band;
    e.band_share = static_cast<double>(band) / std::max<std::size_t>(1, table.pixels.size());
  }
  if (!tilts.empty()) {
    std::nth_element(tilts.begin(), tilts.begin() + tilts.size() / 2, tilts.end());
    e.median_tilt_deg = tilts[tilts.size() / 2];
    int t5 = 0, t10 = 0, t20 = 0;
    for (float t : tilts) t5 += t <= 5.0f, t10 += t <= 10.0f, t20 += t <= 20.0f;
    e.tilt20_share = static_cast<double>(t20) / tilts.size();
    e.flat_share = t20 > 0 ? static_cast<double>(t10) / t20 : std::nan("");
    e.tilt5_share = static_cast<double>(t5) / tilts.size();
    e.tilt10_share = static_cast<double>(t10) / tilts.size();
  }
  // Under the top: the box shrunk by 5 cm on a 5 cm grid.
  constexpr float kCell = 0.05f, kShrink = 0.05f;
  const float half_l = table.extents.x() - kShrink, half_w = table.extents.y() - kShrink;
  if (half_l > 0 && half_w > 0) {
    const int cols = std::max(1, static_cast<int>(2 * half_l / kCell));
    const int rows = std::max(1, static_cast<int>(2 * half_w / kCell));
    std::vector<std::uint8_t> filled(static_cast<std::size_t>(cols) * rows, 0),
        floor(filled.size(), 0);
    for (const Eigen::Vector3f& q : cloud.points) {
      if (!std::isfinite(q.z()) || q.z() > table.top_height - 0.1f) continue;
      const Eigen::Vector2f d = q.head<2>() - table.center;
      const float a = d.dot(table.major_axis) + half_l, b = d.dot(table.minor_axis) + half_w;
      if (a < 0 || b < 0 || a >= 2 * half_l || b >= 2 * half_w) continue;
      const int c = std::min(cols - 1, static_cast<int>(a / kCell));
      const int r = std::min(rows - 1, static_cast<int>(b / kCell));
      const std::size_t cell = static_cast<std::size_t>(r) * cols + c;
      if (q.z() < 0.05f) {
        floor[cell] = 1;
      } else {
        filled[cell] = 1;
      }
    }
    int f = 0, fl = 0;
    for (std::size_t k = 0; k < filled.size(); ++k) f += filled[k], fl += floor[k];
    e.under_filled_share = static_cast<double>(f) / filled.size();
    e.under_floor_share = static_cast<double>(fl) / filled.size();
  }
  return e;
}

std::string formatDiagnosisCounts(const TableDiagnosisCounts& counts) {
  std::ostringstream out;
  out << "true instances:\n";
  for (const auto& [reason, n] : counts.truth) out << "  " << n << "  " << reason << "\n";
  out << "detections:\n";
  for (const auto& [reason, n] : counts.detected) out << "  " << n << "  " << reason << "\n";
  return out.str();
}

}  // namespace findmug::tools
