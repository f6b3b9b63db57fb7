// findmug-eval's measures of the labels around the tables, beside the tables' precision and
// recall: the labels without and with the table-top objects relabelled, the true NYU-40
// classes under the pixels labelled table, and the per-cluster evidence the table-top test
// is chosen on (--table-evidence).
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "eval_report.hpp"
#include "eval_tables.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::tools {

// Where --table-evidence rows go (`csv`, null for none) and the folders whose label40/
// holds the frames' NYU-40 labels.
struct TableEvidenceOut {
  std::ostream* csv = nullptr;
  const std::vector<std::string>* folders = nullptr;
  bool truth = true;  // also the true instances (the same on every seed)
};

// The frame's table-top candidates on its detected tables, and its labels without and with
// their table pixels relabelled Object (the Segmenter's table_objects.relabel).
void measureRelabel(const PreparedFrame& prepared, const LabelImage& predicted,
                    const std::vector<TableCluster>& detected,
                    const std::vector<std::uint8_t>& ground_truth, const SegmenterConfig& config,
                    EvalReport::Relabel& relabel);
// The frame's NYU-40 labels from the first of `folders` whose label40/ has it, or empty.
std::vector<std::uint8_t> nyu40Labels(const std::vector<std::string>& folders,
                                      const std::string& name, std::size_t pixels);
// The true NYU-40 class under every pixel labelled Table (EvalReport::TableByNyu40).
void countTableByNyu40(const std::vector<std::string>& folders,
                       const std::vector<FrameSample>& samples,
                       const std::vector<std::vector<std::uint8_t>>& mrf_pixels,
                       EvalReport::TableByNyu40& out);
// --table-evidence: the CSV header, and one row.
void writeTableEvidenceHeader(std::ostream& out);
void writeTableEvidence(std::ostream& out, const char* source, const TableTopEvidence& e);

}  // namespace findmug::tools
