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
  const std::vector<float>* table_probability = nullptr;        // per pixel forest p(table), or null
  const NormalImage* normals_ground = nullptr;                  // for the horizontal share, or null
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

}  // namespace findmug::tools
