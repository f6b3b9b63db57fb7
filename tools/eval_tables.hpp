// findmug-eval's table diagnosis (--table-report): per frame, the true table
// instances and the detected tables side by side, their IoU, and why each
// unmatched one failed, so that the failure categories can be counted.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/offline/table_metrics.hpp"

namespace findmug::tools {

// What is known of one evaluated frame besides its tables.
struct FrameTableEvidence {
  std::string name;
  int width = 0, height = 0;
  const std::vector<std::uint8_t>* truth_labels = nullptr;      // per pixel, 255 void
  const std::vector<std::uint8_t>* predicted_labels = nullptr;  // per pixel, the final labels
  const std::vector<float>* table_probability = nullptr;  // per pixel forest p(table), or null
  const NormalImage* normals_ground = nullptr;            // for the horizontal share, or null
};

// Failure categories summed over frames (category -> count).
struct TableDiagnosisCounts {
  std::map<std::string, int> truth;     // why a true instance was not matched ("matched" too)
  std::map<std::string, int> detected;  // why a detection matched nothing ("matched" too)
};

// A plain-text block for the frame: every true instance and detection with
// its size, top height, top area, mean p(table), mean confidence and share
// of horizontal points; the non-zero IoUs; and one reason per unmatched
// instance or detection, also added to `counts`.
std::string diagnoseFrameTables(const FrameTableEvidence& frame,
                                const std::vector<TableCluster>& truth,
                                const std::vector<TableCluster>& detected,
                                const std::vector<TableMatch>& matches,
                                TableDiagnosisCounts& counts);

std::string formatDiagnosisCounts(const TableDiagnosisCounts& counts);

// What tells a table top from a bed or sofa top, measured on one detected table for the
// table-top test's evidence (--table-evidence): its true NYU-40 class (the most frequent
// under its pixels, 0 without label40/) and shape measures from the cloud and normals.
struct TableTopEvidence {
  std::string frame;
  int nyu40 = 0;             // the most frequent true NYU-40 class under its pixels
  double nyu40_share = 0.0;  // that class's share of its labelled pixels
  int points = 0;
  double top_height_m = 0, length_m = 0, width_m = 0, top_area_m2 = 0;
  // Heights of the points within tables.top_band_m of the top: standard deviation, and
  // the share of them within 1.5 cm of the top height.
  double band_spread_m = 0, band_flat_share = 0;
  double band_share = 0;  // share of the cluster's points in the band
  // Normals of the band's points: the median tilt from vertical, and the shares within 5,
  // 10 and 20 degrees.
  double median_tilt_deg = 0, tilt5_share = 0, tilt10_share = 0, tilt20_share = 0;
  // tilt10_share / tilt20_share: the table-top test's TableCluster::flat_share at the
  // shipped tilts (10 and 20 degrees), NaN without a point within 20 degrees.
  double flat_share = 0;
  // The box's inside (shrunk by 5 cm) on a 5 cm grid: the share of its cells holding a
  // point between 5 cm above the floor and 10 cm below the top (something under the top)
  // and the share holding a floor point (below 5 cm: the floor seen under it).
  double under_filled_share = 0, under_floor_share = 0;
};

// `truth40`: the frame's NYU-40 labels (0 unlabelled) or null.
TableTopEvidence measureTableTop(const std::string& frame, const OrganizedCloud& cloud_ground,
                                 const NormalImage& normals_ground, const TableCluster& table,
                                 float top_band_m, const std::vector<std::uint8_t>* truth40);

}  // namespace findmug::tools
