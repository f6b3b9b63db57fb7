// findmug/frame/dataset.hpp — labelled RGB-D datasets in the NYU-style folder layout.
//
//   DIR/rgb/NAME.png     RGB8
//   DIR/depth/NAME.png   uint16, millimetres, 0 = missing
//   DIR/label8/NAME.png  uint8, findmug ids (0..7), 255 void       — or —
//   DIR/label40/NAME.png uint8, NYU-40 ids (1..40), 0 void, mapped 40 -> 8 by a CSV
//                        (label folders are optional when DatasetOptions::require_labels
//                        is false: replay of one's own recordings needs none)
//   DIR/intrinsics.yaml  optional: fx fy cx cy (default: NYU's Kinect calibration)
//   DIR/extrinsics.csv   optional: name,height_m,pitch_rad,roll_rad per frame (synthetic data)
//   DIR/gravity.csv      optional: name,up_x,up_y,up_z per frame: the "up" direction (against
//                        gravity) in camera coordinates (x right, y down, z forward), any length
//
// For NYU Depth V2 folders (frames named by NYU index, "0001".."1449") the
// per-frame gravity can instead come from NYU's camera_rotations_NYU.txt
// (DatasetOptions::nyu_rotations_file); gravity.csv rows take precedence.
//
// Frames are read lazily, one at a time, so a large folder costs no memory.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "findmug/frame/frame.hpp"
#include "findmug/labels/labels.hpp"

namespace findmug {

// NYU Depth V2 RGB camera (toolbox camera_params.m).
inline constexpr CameraIntrinsics kNyuIntrinsics{518.85790117450188, 519.46961112127485,
                                                 325.58244941119034, 253.73616633400465};

// Maps source label ids (0..255) to findmug ids; unmapped ids are an error.
struct LabelMapping {
  std::array<int, 256> to_findmug;  // -1 = not in the mapping
  std::string source;               // file it came from, for messages
  LabelMapping() { to_findmug.fill(-1); }
};

// CSV with header `source_id,findmug_label` (findmug_label a name from
// kLabelNames or "void"). Throws on unknown names, duplicate or bad ids.
LabelMapping loadLabelMapping(const std::string& csv_path);
// Same, from CSV text already in memory; `source` names it in messages.
LabelMapping parseLabelMapping(const std::string& csv_text, const std::string& source);

// The NYU-40 -> findmug-8 mapping that ships with the project
// (models/nyu40_to_findmug8.csv, compiled in).
const LabelMapping& defaultNyu40Mapping();

// NYU Depth V2's per-frame gravity-aligning rotations
// (nyuv2_meta/camera_rotations_NYU.txt): 1449 3x3 matrices of three
// whitespace-separated numbers per row, matrices separated by blank lines,
// in NYU index order (1-based).
//
// Convention, measured on the 14 labelled frames whose floor labels give a
// plane (perf-log §1d): R, read row by row as written, maps camera
// coordinates (x right, y down, z forward) to a gravity-aligned frame whose
// y axis points DOWN, so "up" in camera coordinates is -R^T (0,1,0), i.e.
// minus row 1 (0-based) of R. It is 0.75..6.35 degrees (median 3.0) from the
// labelled floor's normal; the transposed reading is up to 21.7 degrees off.
struct NyuRotations {
  std::string source;                          // file, for messages
  std::vector<std::array<double, 9>> rotations;  // row-major, index 0 = NYU index 1
  // Unit "up" in camera coordinates for a 1-based NYU index; throws
  // findmug::Error naming the file when the index is out of range.
  std::array<double, 3> upForIndex(long nyu_index) const;
};
NyuRotations loadNyuRotations(const std::string& path);
// Same, from text already in memory. Errors name `source` and the line:
// a field that is not a finite number, a row without exactly 3 numbers, a
// matrix without exactly 3 rows, a matrix far from a rotation.
NyuRotations parseNyuRotations(const std::string& text, const std::string& source);
// "Up" in camera coordinates from one matrix (row-major) of that file.
std::array<double, 3> nyuUpFromRotation(const std::array<double, 9>& rotation);

// $FINDMUG_DATA/nyuv2_meta/camera_rotations_NYU.txt (see defaultNyu894To40CsvPath).
std::string defaultNyuRotationsPath();

// Reads DIR/gravity.csv (header `name,up_x,up_y,up_z`); errors name the file and line.
std::vector<std::pair<std::string, std::array<double, 3>>> loadGravityCsv(const std::string& path);

// NYU-40 class ids are 1..40, NYU-13 ids 1..13; 0 = unlabelled.
inline constexpr int kNyu40Classes = 40;
inline constexpr int kNyu13Classes = 13;

struct LabeledFrame {
  std::string name;
  RgbdFrame frame;
  std::vector<std::uint8_t> labels;  // findmug ids, kVoidLabel = no ground truth
  // Finer class ids (0 = unlabelled) per pixel: from a folder's label40/ or
  // label13/ when asked for (DatasetOptions::fine_labels_folder,
  // training.split_labels), and NYU-40 ids always from NyuMatFile; empty
  // otherwise. 0 wherever `labels` is void.
  std::vector<std::uint8_t> fine_labels;
};

struct DatasetOptions {
  std::optional<std::string> mapping_csv;  // label40 -> 8; default: the shipped mapping
  // NYU's invalid border (projection mask): pixels outside are void and get
  // no depth. 1-based inclusive rows 45..471, cols 41..601 in the NYU toolbox,
  // i.e. a 427x561 valid region of a 640x480 frame: 0-based rows 44..470,
  // cols 40..600. Applied only to folders that use NYU's calibration (no
  // intrinsics.yaml and no `intrinsics` override): other sensors and the
  // synthetic generator have no such border.
  bool mask_nyu_border = true;
  int border_top = 44, border_bottom = 9, border_left = 40, border_right = 39;  // pixels cut
  std::optional<CameraIntrinsics> intrinsics;  // overrides intrinsics.yaml / NYU default
  // NYU's camera_rotations_NYU.txt: frames whose name is an NYU index
  // ("0001".."1449") get their gravity from it. A frame name that is not a
  // number, or an index beyond the file, is an error naming both.
  std::optional<std::string> nyu_rotations_file;
  // Training and evaluation need ground truth; replay does not. When false, a
  // folder without label8/ and label40/ lists the frames present in rgb/ and
  // depth/, and load() returns labels that are all kVoidLabel.
  bool require_labels = true;
  // Also read <fine_labels_folder>/<name>.png ("label40": ids 0..40, or
  // "label13": ids 0..13) into LabeledFrame::fine_labels, for
  // training.split_labels. "" = not read. A folder without it is then an error.
  std::string fine_labels_folder;
  // The setting that asked for fine_labels_folder (e.g. "learner.classes = nyu13"),
  // named in the error when a folder lacks it, so the user knows what to change.
  std::string fine_labels_asked_by = "training.split_labels";
  // A folder without fine_labels_folder is then read with the 8 labels only
  // (LabeledFrame::fine_labels empty) rather than refused: internal classes
  // infer the finer class of such frames' patches (inferMissingFineLabels),
  // so a robot owner's frames from the Label page can join the NYU ones.
  bool fine_labels_optional = false;
};

class DatasetFolder {
 public:
  // Lists frames (names present in rgb/, depth/ and a label folder, if any).
  // Throws when the folder or a required sub-folder is missing or empty.
  DatasetFolder(const std::string& dir, const DatasetOptions& options = {});

  std::size_t size() const { return names_.size(); }
  const std::vector<std::string>& names() const { return names_; }
  const std::string& dir() const { return dir_; }
  // False for an unlabelled folder opened with require_labels = false.
  bool hasLabels() const { return has_labels_; }
  // Reads and validates frame i; throws findmug::Error naming the file on
  // size mismatch, wrong bit depth, or label ids outside the mapping.
  LabeledFrame load(std::size_t i) const;

 private:
  std::string dir_;
  DatasetOptions options_;
  std::vector<std::string> names_;
  bool has_label8_ = false;
  bool has_fine_labels_ = false;  // options_.fine_labels_folder exists here
  bool has_labels_ = true;
  LabelMapping mapping_;
  CameraIntrinsics intrinsics_;
  bool nyu_calibration_ = false;  // NYU default intrinsics: the NYU border applies
  std::vector<std::optional<CameraExtrinsics>> extrinsics_;
  std::vector<std::optional<std::array<double, 3>>> gravity_;
};

// Writes one frame in the folder layout above (label8), used by the
// synthetic generator and the .mat converter.
void writeLabeledFrame(const std::string& dir, const LabeledFrame& frame);

// $FINDMUG_DATA/nyuv2_meta/nyu894_to_40.csv, with FINDMUG_DATA defaulting to
// the data folder configured at build time (FINDMUG_DEFAULT_DATA_DIR).
std::string defaultNyu894To40CsvPath();

}  // namespace findmug
