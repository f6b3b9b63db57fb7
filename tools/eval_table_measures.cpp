// findmug-eval's measures of the labels around the tables (eval_table_measures.hpp).
#include "eval_table_measures.hpp"

#include <filesystem>

#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/objects/table_objects.hpp"

namespace findmug::tools {

// The frame's table-top candidates on its detected tables, and its labels without and
// with their table pixels relabelled Object (the Segmenter's table_objects.relabel). The
// labels here are hole-filled already (the Segmenter relabels before the fill): the
// candidates are made of pixels with depth, which the fill never changes.
void measureRelabel(const PreparedFrame& prepared, const LabelImage& predicted,
                    const std::vector<TableCluster>& detected,
                    const std::vector<std::uint8_t>& ground_truth, const SegmenterConfig& config,
                    EvalReport::Relabel& relabel) {
  const TableObjectDetection candidates =
      findTableObjects(prepared.cloud_ground, predicted, detected, config.table_objects);
  LabelImage relabelled = predicted;
  relabel.pixels_changed +=
      static_cast<std::uint64_t>(relabelTableObjects(candidates.objects, relabelled));
  relabel.candidates += static_cast<int>(candidates.objects.size());
  ++relabel.frames;
  relabel.without.add(ground_truth, predicted.labels);
  relabel.with.add(ground_truth, relabelled.labels);
}

// The frame's NYU-40 labels from the first of `folders` whose label40/ has it, or empty.
std::vector<std::uint8_t> nyu40Labels(const std::vector<std::string>& folders,
                                      const std::string& name, std::size_t pixels) {
  for (const std::string& folder : folders) {
    const auto path = std::filesystem::path(folder) / "label40" / (name + ".png");
    if (!std::filesystem::exists(path)) continue;
    Image<std::uint8_t> fine = readPng8(path.string());
    if (fine.pixels.size() != pixels)
      throw Error(path.string() + ": " + std::to_string(fine.pixels.size()) + " labels for " +
                  std::to_string(pixels) + " pixels");
    return std::move(fine.pixels);
  }
  return {};
}

// The true NYU-40 class under every pixel labelled Table (EvalReport::TableByNyu40), for
// the frames whose label40/NAME.png is in one of `folders` (NYU folders; others have none);
// `mrf_pixels[f]` the final labels of samples[f] (empty: not evaluated).
void countTableByNyu40(const std::vector<std::string>& folders,
                       const std::vector<FrameSample>& samples,
                       const std::vector<std::vector<std::uint8_t>>& mrf_pixels,
                       EvalReport::TableByNyu40& out) {
  constexpr auto kTable = static_cast<std::uint8_t>(Label::Table);
  for (std::size_t f = 0; f < samples.size(); ++f) {
    const std::vector<std::uint8_t>& predicted = mrf_pixels[f];
    if (predicted.empty()) continue;
    const std::vector<std::uint8_t> fine = nyu40Labels(folders, samples[f].name, predicted.size());
    if (fine.empty()) continue;
    for (std::size_t p = 0; p < predicted.size(); ++p) {
      const std::uint8_t c = fine[p];
      if (c == 0 || c > kNyu40Classes || samples[f].ground_truth[p] == kVoidLabel) continue;
      ++out.pixels[c];
      out.labelled_table[c] += predicted[p] == kTable;
    }
    ++out.frames;
  }
}

void writeTableEvidenceHeader(std::ostream& out) {
  out << "source,frame,nyu40,nyu40_share,points,top_height_m,length_m,width_m,top_area_m2,"
         "band_spread_m,band_flat_share,band_share,median_tilt_deg,tilt5_share,tilt10_share,"
         "tilt20_share,flat_share,under_filled_share,under_floor_share\n";
}

void writeTableEvidence(std::ostream& out, const char* source, const TableTopEvidence& e) {
  out << source << "," << e.frame << "," << (e.nyu40 > 0 ? nyu40ClassName(e.nyu40) : "none") << ","
      << e.nyu40_share << "," << e.points << "," << e.top_height_m << "," << e.length_m << ","
      << e.width_m << "," << e.top_area_m2 << "," << e.band_spread_m << "," << e.band_flat_share
      << "," << e.band_share << "," << e.median_tilt_deg << "," << e.tilt5_share << ","
      << e.tilt10_share << "," << e.tilt20_share << "," << e.flat_share << ","
      << e.under_filled_share << "," << e.under_floor_share << "\n";
}

}  // namespace findmug::tools
