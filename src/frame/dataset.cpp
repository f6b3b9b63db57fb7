// Labelled RGB-D datasets in the NYU-style folder layout (see dataset.hpp).
//
// Every check here exists because the mistake it catches is easy to make and
// silent downstream: depth written as 8 bit or in metres, a label40 folder
// read as label8, a label id the mapping does not know, colour and depth of
// different sizes. Each is reported with the file and the offending value.
#include "findmug/frame/dataset.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "common/csv_rows.hpp"
#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/frame/image_io.hpp"

namespace findmug {

namespace generated {
extern const char* const kNyu40MappingCsv;
extern const char* const kNyu40MappingCsvPath;
extern const char* const kDefaultDataDir;
}  // namespace generated

namespace fs = std::filesystem;

namespace {

// Depth plausibility bounds for the median of valid pixels, in millimetres.
// Indoor scenes seen by a Kinect-class sensor have medians of ~0.5..8 m;
// below 100 the file is almost certainly metres or decimetres stored as
// integers, above 20000 a different unit (e.g. 1/5000 m as in TUM/ICL).
constexpr std::uint16_t kMinPlausibleMedianMm = 100;
constexpr std::uint16_t kMaxPlausibleMedianMm = 20000;

// Strict integer parse: the whole field must be a number.
bool parseInt(const std::string& text, long& value) {
  const auto parsed = parseInteger(text);
  if (!parsed) return false;
  value = static_cast<long>(*parsed);
  return true;
}

// Strict floating-point parse: a finite number and nothing else.
bool parseDouble(const std::string& text, double& value) {
  const auto parsed = parseNumber(text);
  if (!parsed) return false;
  value = *parsed;
  return true;
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(path + ": read failed");
  return text.str();
}

// Id of a findmug label name ("void" -> kVoidLabel), or -1.
int labelIdFromName(const std::string& name) {
  if (name == "void") return kVoidLabel;
  for (int i = 0; i < kNumLabels; ++i) {
    if (kLabelNames[static_cast<std::size_t>(i)] == name) return i;
  }
  return -1;
}

std::string sizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

CameraIntrinsics readIntrinsicsYaml(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw Error(path + ": cannot parse YAML (" + e.what() + ")");
  }
  if (!root.IsMap()) throw Error(path + ": expected a map with fx, fy, cx, cy");
  auto get = [&](const char* key) {
    const YAML::Node node = root[key];
    if (!node) throw Error(path + ": missing key '" + key + "'");
    double value = 0.0;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      throw Error(path + ": '" + key + "' is not a number");
    }
    if (!std::isfinite(value)) throw Error(path + ": '" + key + "' is not finite");
    return value;
  };
  CameraIntrinsics k;
  k.fx = get("fx");
  k.fy = get("fy");
  k.cx = get("cx");
  k.cy = get("cy");
  if (k.fx <= 0.0 || k.fy <= 0.0) {
    std::ostringstream msg;
    msg << path << ": focal lengths must be positive (fx=" << k.fx << " fy=" << k.fy << ")";
    throw Error(msg.str());
  }
  return k;
}

struct ExtrinsicsRow {
  std::string name;
  CameraExtrinsics extrinsics;
};

constexpr const char* kExtrinsicsHeader = "name,height_m,pitch_rad,roll_rad";

// Rows "name,a,b,c" of a per-frame CSV file with the given header: three
// finite numbers per frame, names unique. Errors name the file and line.
struct NamedTriple {
  std::string name;
  std::array<double, 3> values{};
  std::string where;  // "file:line", for the caller's own checks
};

std::vector<NamedTriple> readPerFrameCsv(const std::string& path, const std::string& header) {
  const auto columns = detail::splitCsvFields(header);
  std::vector<NamedTriple> rows;
  std::set<std::string> seen;
  for (detail::CsvRow& csv : detail::readCsvRows(readTextFile(path), path, header)) {
    NamedTriple row;
    row.name = csv.fields[0];
    row.where = std::move(csv.where);
    if (row.name.empty()) throw Error(row.where + ": empty frame name");
    for (std::size_t c = 0; c < 3; ++c) {
      if (!parseDouble(csv.fields[c + 1], row.values[c])) {
        throw Error(row.where + ": " + columns[c + 1] + " '" + csv.fields[c + 1] +
                    "' is not a finite number");
      }
    }
    if (!seen.insert(row.name).second) {
      throw Error(row.where + ": duplicate frame '" + row.name + "'");
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<ExtrinsicsRow> readExtrinsicsCsv(const std::string& path) {
  std::vector<ExtrinsicsRow> rows;
  for (const NamedTriple& t : readPerFrameCsv(path, kExtrinsicsHeader)) {
    rows.push_back({t.name, CameraExtrinsics{t.values[0], t.values[1], t.values[2]}});
  }
  return rows;
}

// Stems of the *.png files in `dir` (regular files only).
std::set<std::string> pngStems(const fs::path& dir) {
  std::set<std::string> stems;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file() && it->path().extension() == ".png") {
      stems.insert(it->path().stem().string());
    }
  }
  if (ec) throw Error(dir.string() + ": cannot list (" + ec.message() + ")");
  return stems;
}

// "id 99 (12 pixels), id 41 (3 pixels)" for ids whose lookup is -1.
std::string unmappedIds(const std::vector<std::uint8_t>& ids, const std::array<int, 256>& lookup) {
  std::array<std::size_t, 256> counts{};
  for (auto id : ids) ++counts[id];
  std::string out;
  for (int id = 0; id < 256; ++id) {
    if (counts[static_cast<std::size_t>(id)] == 0 || lookup[static_cast<std::size_t>(id)] >= 0) {
      continue;
    }
    if (!out.empty()) out += ", ";
    out += "id " + std::to_string(id) + " (" +
           std::to_string(counts[static_cast<std::size_t>(id)]) + " pixels)";
  }
  return out;
}

// Valid label8 ids: 0..7 and void.
const std::array<int, 256>& label8Identity() {
  static const std::array<int, 256> identity = [] {
    std::array<int, 256> table;
    table.fill(-1);
    for (int i = 0; i < kNumLabels; ++i) table[static_cast<std::size_t>(i)] = i;
    table[kVoidLabel] = kVoidLabel;
    return table;
  }();
  return identity;
}

void checkFrameName(const std::string& name) {
  if (name.empty() || name.find_first_of("/\\,\n\r") != std::string::npos || name == "." ||
      name == "..") {
    throw Error("invalid frame name '" + name + "' (must be non-empty, without / \\ , or newline)");
  }
}

std::string formatDouble(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

void writeTextFileAtomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(tmp.string() + ": cannot open for writing");
    out << text;
    out.flush();
    if (!out) throw Error(tmp.string() + ": write failed");
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw Error(path.string() + ": cannot replace (" + ec.message() + ")");
}

// Whitespace-separated fields of a line.
std::vector<std::string> splitWhitespace(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  std::string field;
  while (in >> field) fields.push_back(field);
  return fields;
}

constexpr const char* kGravityHeader = "name,up_x,up_y,up_z";

// A gravity direction must be a usable direction; it is normalised here.
std::array<double, 3> normalizedUp(const std::array<double, 3>& up, const std::string& where) {
  const double norm = std::sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
  if (!(norm > 1e-6)) {
    throw Error(where + ": up direction (" + formatDouble(up[0]) + ", " + formatDouble(up[1]) +
                ", " + formatDouble(up[2]) + ") has zero length");
  }
  return {up[0] / norm, up[1] / norm, up[2] / norm};
}

}  // namespace

// ---------------------------------------------------------------------------
// Per-frame gravity

std::array<double, 3> nyuUpFromRotation(const std::array<double, 9>& r) {
  // Row 1 of R (0-based) is the gravity-aligned frame's y axis ("down")
  // expressed in camera coordinates; "up" is its negative. See dataset.hpp.
  return {-r[3], -r[4], -r[5]};
}

NyuRotations parseNyuRotations(const std::string& text, const std::string& source) {
  NyuRotations out;
  out.source = source;
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  std::array<double, 9> current{};
  int rows = 0;
  int first_row_line = 0;
  auto finishMatrix = [&]() {
    if (rows == 0) return;
    if (rows != 3) {
      throw Error(source + ":" + std::to_string(first_row_line) + ": matrix " +
                  std::to_string(out.rotations.size() + 1) + " has " + std::to_string(rows) +
                  " rows, expected 3");
    }
    // R R^T = I within the file's 6 printed digits.
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        double dot = 0;
        for (int k = 0; k < 3; ++k) dot += current[3 * a + k] * current[3 * b + k];
        if (std::abs(dot - (a == b ? 1.0 : 0.0)) > 1e-3) {
          throw Error(source + ":" + std::to_string(first_row_line) + ": matrix " +
                      std::to_string(out.rotations.size() + 1) + " is not a rotation (row " +
                      std::to_string(a) + " . row " + std::to_string(b) + " = " +
                      formatDouble(dot) + ")");
        }
      }
    }
    out.rotations.push_back(current);
    rows = 0;
  };
  while (std::getline(in, line)) {
    ++line_number;
    const auto fields = splitWhitespace(line);
    if (fields.empty()) {
      finishMatrix();
      continue;
    }
    const std::string where = source + ":" + std::to_string(line_number);
    if (fields.size() != 3) {
      throw Error(where + ": expected 3 numbers in a matrix row, found " +
                  std::to_string(fields.size()));
    }
    if (rows == 3) {
      throw Error(where + ": matrix " + std::to_string(out.rotations.size() + 1) +
                  " has more than 3 rows (matrices are separated by blank lines)");
    }
    if (rows == 0) first_row_line = line_number;
    for (int c = 0; c < 3; ++c) {
      double value = 0;
      if (!parseDouble(fields[static_cast<std::size_t>(c)], value)) {
        throw Error(where + ": '" + fields[static_cast<std::size_t>(c)] +
                    "' is not a finite number");
      }
      current[static_cast<std::size_t>(3 * rows + c)] = value;
    }
    ++rows;
  }
  finishMatrix();
  if (out.rotations.empty()) throw Error(source + ": no rotation matrix");
  return out;
}

NyuRotations loadNyuRotations(const std::string& path) {
  return parseNyuRotations(readTextFile(path), path);
}

std::array<double, 3> NyuRotations::upForIndex(long nyu_index) const {
  if (nyu_index < 1 || static_cast<std::size_t>(nyu_index) > rotations.size()) {
    throw Error(source + ": NYU index " + std::to_string(nyu_index) + " out of range (file has " +
                std::to_string(rotations.size()) + " matrices, indices 1.." +
                std::to_string(rotations.size()) + ")");
  }
  return nyuUpFromRotation(rotations[static_cast<std::size_t>(nyu_index - 1)]);
}

std::string defaultNyuRotationsPath() {
  const char* env = std::getenv("FINDMUG_DATA");
  const std::string root = env && *env ? env : generated::kDefaultDataDir;
  return root + "/nyuv2_meta/camera_rotations_NYU.txt";
}

std::vector<std::pair<std::string, std::array<double, 3>>> loadGravityCsv(const std::string& path) {
  std::vector<std::pair<std::string, std::array<double, 3>>> rows;
  for (const NamedTriple& t : readPerFrameCsv(path, kGravityHeader)) {
    rows.emplace_back(t.name, normalizedUp(t.values, t.where));
  }
  return rows;
}

// ---------------------------------------------------------------------------
// Label mappings

LabelMapping parseLabelMapping(const std::string& csv_text, const std::string& source) {
  LabelMapping mapping;
  mapping.source = source;
  int entries = 0;
  for (const detail::CsvRow& row :
       detail::readCsvRows(csv_text, source, "source_id,findmug_label")) {
    long id = 0;
    if (!parseInt(row.fields[0], id) || id < 0 || id > 255) {
      throw Error(row.where + ": source_id '" + row.fields[0] + "' is not an integer in 0..255");
    }
    const int label = labelIdFromName(row.fields[1]);
    if (label < 0) {
      throw Error(row.where + ": unknown findmug_label '" + row.fields[1] +
                  "' (expected one of unknown, floor, wall, ceiling, table, chair, cabinet, "
                  "object, void)");
    }
    auto& slot = mapping.to_findmug[static_cast<std::size_t>(id)];
    if (slot >= 0) throw Error(row.where + ": duplicate source_id " + std::to_string(id));
    slot = label;
    ++entries;
  }
  if (entries == 0) throw Error(source + ": mapping has no entries");
  return mapping;
}

LabelMapping loadLabelMapping(const std::string& csv_path) {
  return parseLabelMapping(readTextFile(csv_path), csv_path);
}

const LabelMapping& defaultNyu40Mapping() {
  static const LabelMapping mapping = parseLabelMapping(
      generated::kNyu40MappingCsv, std::string(generated::kNyu40MappingCsvPath) + " (compiled in)");
  return mapping;
}

// ---------------------------------------------------------------------------
// DatasetFolder

DatasetFolder::DatasetFolder(const std::string& dir, const DatasetOptions& options)
    : dir_(dir), options_(options) {
  const fs::path root(dir);
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw Error(dir + ": dataset folder does not exist");
  for (const char* sub : {"rgb", "depth"}) {
    if (!fs::is_directory(root / sub, ec)) {
      throw Error(dir + ": missing sub-folder '" + sub +
                  "/' (expected rgb/, depth/, label8/ or "
                  "label40/)");
    }
  }
  if (fs::is_directory(root / "label8", ec)) {
    has_label8_ = true;
  } else if (!fs::is_directory(root / "label40", ec)) {
    if (options.require_labels) {
      throw Error(dir + ": missing label folder (neither label8/ nor label40/)");
    }
    has_labels_ = false;
  }
  const char* label_dir = has_labels_ ? (has_label8_ ? "label8" : "label40") : "rgb";
  if (!options.fine_labels_folder.empty()) {
    if (options.fine_labels_folder != "label40" && options.fine_labels_folder != "label13")
      throw Error(dir + ": fine labels folder '" + options.fine_labels_folder +
                  "' (expected label40 or label13)");
    has_fine_labels_ = fs::is_directory(root / options.fine_labels_folder, ec);
    if (!has_fine_labels_ && !options.fine_labels_optional)
      throw Error(dir + ": " + options.fine_labels_folder +
                  "/ labels asked for (" + options.fine_labels_asked_by + ") but there is no " +
                  options.fine_labels_folder + "/ folder");
  }

  if (has_labels_ && !has_label8_) {
    mapping_ = options.mapping_csv ? loadLabelMapping(*options.mapping_csv) : defaultNyu40Mapping();
  }
  if (options.mask_nyu_border && (options.border_top < 0 || options.border_bottom < 0 ||
                                  options.border_left < 0 || options.border_right < 0)) {
    throw Error(dir + ": negative NYU border width in dataset options");
  }

  const auto rgb = pngStems(root / "rgb");
  const auto depth = pngStems(root / "depth");
  const auto labels = pngStems(root / label_dir);
  if (rgb.empty()) throw Error((root / "rgb").string() + ": no PNG files");
  if (depth.empty()) throw Error((root / "depth").string() + ": no PNG files");
  if (labels.empty()) throw Error((root / label_dir).string() + ": no PNG files");
  for (const auto& name : rgb) {
    if (depth.count(name) && labels.count(name)) names_.push_back(name);
  }
  if (names_.empty()) {
    if (!has_labels_) throw Error(dir + ": no frame has both rgb/NAME.png and depth/NAME.png");
    throw Error(dir + ": no frame has all of rgb/NAME.png, depth/NAME.png and " + label_dir +
                "/NAME.png");
  }

  if (options.intrinsics) {
    intrinsics_ = *options.intrinsics;
  } else if (fs::exists(root / "intrinsics.yaml", ec)) {
    intrinsics_ = readIntrinsicsYaml((root / "intrinsics.yaml").string());
  } else {
    intrinsics_ = kNyuIntrinsics;
    nyu_calibration_ = true;
  }

  extrinsics_.assign(names_.size(), std::nullopt);
  if (fs::exists(root / "extrinsics.csv", ec)) {
    const auto rows = readExtrinsicsCsv((root / "extrinsics.csv").string());
    std::map<std::string, std::size_t> index;
    for (std::size_t i = 0; i < names_.size(); ++i) index[names_[i]] = i;
    for (const auto& row : rows) {
      // Rows for frames not (or no longer) in the folder are harmless.
      if (auto it = index.find(row.name); it != index.end()) {
        extrinsics_[it->second] = row.extrinsics;
      }
    }
  }

  gravity_.assign(names_.size(), std::nullopt);
  if (options.nyu_rotations_file) {
    const NyuRotations rotations = loadNyuRotations(*options.nyu_rotations_file);
    for (std::size_t i = 0; i < names_.size(); ++i) {
      long index = 0;
      if (!parseInt(names_[i], index)) {
        throw Error(dir + ": frame '" + names_[i] + "' is not named by an NYU index, so " +
                    rotations.source + " cannot give its gravity (use gravity.csv)");
      }
      gravity_[i] = rotations.upForIndex(index);
    }
  }
  if (fs::exists(root / "gravity.csv", ec)) {
    std::map<std::string, std::size_t> index;
    for (std::size_t i = 0; i < names_.size(); ++i) index[names_[i]] = i;
    for (const auto& [name, up] : loadGravityCsv((root / "gravity.csv").string())) {
      if (auto it = index.find(name); it != index.end()) gravity_[it->second] = up;
    }
  }
}

LabeledFrame DatasetFolder::load(std::size_t i) const {
  if (i >= names_.size()) {
    throw Error(dir_ + ": frame index " + std::to_string(i) + " out of range (" +
                std::to_string(names_.size()) + " frames)");
  }
  const std::string& name = names_[i];
  const fs::path root(dir_);
  const std::string rgb_path = (root / "rgb" / (name + ".png")).string();
  const std::string depth_path = (root / "depth" / (name + ".png")).string();
  const std::string label_path =
      (root / (has_label8_ ? "label8" : "label40") / (name + ".png")).string();

  const auto rgb = readPngRgb(rgb_path);
  Image<std::uint16_t> depth;
  try {
    depth = readPng16(depth_path);
  } catch (const Error& e) {
    throw Error(std::string("depth not uint16 millimetres: ") + e.what());
  }
  // Unlabelled replay: every pixel void, checked like a label image below.
  const auto label_ids =
      has_labels_ ? readPng8(label_path)
                  : Image<std::uint8_t>{rgb.width, rgb.height,
                                        std::vector<std::uint8_t>(rgb.pixels.size(), kVoidLabel)};

  if (depth.width != rgb.width || depth.height != rgb.height) {
    throw Error(depth_path + " is " + sizeText(depth.width, depth.height) + " but " + rgb_path +
                " is " + sizeText(rgb.width, rgb.height));
  }
  if (label_ids.width != rgb.width || label_ids.height != rgb.height) {
    throw Error(label_path + " is " + sizeText(label_ids.width, label_ids.height) + " but " +
                rgb_path + " is " + sizeText(rgb.width, rgb.height));
  }

  // Unit check on the median of valid depth: cheap (nth_element) and it is
  // what distinguishes mm from metres/other scales robustly against outliers.
  {
    std::vector<std::uint16_t> valid;
    valid.reserve(depth.pixels.size());
    for (auto d : depth.pixels) {
      if (d != 0) valid.push_back(d);
    }
    if (valid.empty()) throw Error(depth_path + ": no valid depth pixel (all 0)");
    auto mid = valid.begin() + static_cast<long>(valid.size() / 2);
    std::nth_element(valid.begin(), mid, valid.end());
    if (*mid < kMinPlausibleMedianMm || *mid > kMaxPlausibleMedianMm) {
      throw Error(depth_path + ": depth does not look like millimetres (median " +
                  std::to_string(*mid) + ", expected " + std::to_string(kMinPlausibleMedianMm) +
                  ".." + std::to_string(kMaxPlausibleMedianMm) + ")");
    }
  }

  const auto& lookup = (has_label8_ || !has_labels_) ? label8Identity() : mapping_.to_findmug;
  if (auto bad = unmappedIds(label_ids.pixels, lookup); !bad.empty()) {
    throw Error(label_path + ": label " + bad + " not in " +
                (has_label8_ ? std::string("the findmug ids 0..7, 255") : mapping_.source));
  }

  LabeledFrame out;
  out.name = name;
  RgbdFrame& frame = out.frame;
  frame.width = rgb.width;
  frame.height = rgb.height;
  frame.rgb = rgb.pixels;
  frame.depth_mm = std::move(depth.pixels);
  frame.intrinsics = intrinsics_;
  frame.extrinsics = extrinsics_[i];
  frame.gravity_up = gravity_[i];
  frame.seq = static_cast<std::int64_t>(i);
  frame.source = rgb_path;
  out.labels.resize(label_ids.pixels.size());
  for (std::size_t p = 0; p < label_ids.pixels.size(); ++p) {
    out.labels[p] = static_cast<std::uint8_t>(lookup[label_ids.pixels[p]]);
  }

  if (has_fine_labels_) {
    const std::string fine_path = (root / options_.fine_labels_folder / (name + ".png")).string();
    const int max_id = options_.fine_labels_folder == "label13" ? kNyu13Classes : kNyu40Classes;
    auto fine = readPng8(fine_path);
    if (fine.width != rgb.width || fine.height != rgb.height) {
      throw Error(fine_path + " is " + sizeText(fine.width, fine.height) + " but " + rgb_path +
                  " is " + sizeText(rgb.width, rgb.height));
    }
    for (std::size_t p = 0; p < fine.pixels.size(); ++p) {
      if (fine.pixels[p] > max_id) {
        throw Error(fine_path + ": label " + std::to_string(fine.pixels[p]) + " at pixel " +
                    std::to_string(p) + " is not an NYU-" + std::to_string(max_id) + " id (0.." +
                    std::to_string(max_id) + ")");
      }
      // Unlabelled in the coarse labels = unlabelled here too.
      if (out.labels[p] == kVoidLabel) fine.pixels[p] = 0;
    }
    out.fine_labels = std::move(fine.pixels);
  }

  if (options_.mask_nyu_border && nyu_calibration_) {
    const int x0 = options_.border_left, x1 = frame.width - options_.border_right;
    const int y0 = options_.border_top, y1 = frame.height - options_.border_bottom;
    if (x0 >= x1 || y0 >= y1) {
      throw Error(rgb_path + ": NYU border mask (" + std::to_string(options_.border_top) + "/" +
                  std::to_string(options_.border_bottom) + "/" +
                  std::to_string(options_.border_left) + "/" +
                  std::to_string(options_.border_right) + " px) leaves nothing of a " +
                  sizeText(frame.width, frame.height) + " frame");
    }
    for (int y = 0; y < frame.height; ++y) {
      const bool row_inside = y >= y0 && y < y1;
      for (int x = 0; x < frame.width; ++x) {
        if (row_inside && x >= x0 && x < x1) continue;
        const auto p = static_cast<std::size_t>(y) * frame.width + x;
        out.labels[p] = kVoidLabel;
        if (!out.fine_labels.empty()) out.fine_labels[p] = 0;
        frame.depth_mm[p] = 0;
      }
    }
  }
  validateFrame(frame);
  return out;
}

// ---------------------------------------------------------------------------
// Writing

void writeLabeledFrame(const std::string& dir, const LabeledFrame& labeled) {
  checkFrameName(labeled.name);
  const RgbdFrame& frame = labeled.frame;
  validateFrame(frame);
  const auto pixels = static_cast<std::size_t>(frame.width) * frame.height;
  if (labeled.labels.size() != pixels) {
    throw Error("frame '" + labeled.name + "': " + std::to_string(labeled.labels.size()) +
                " labels for " + std::to_string(pixels) + " pixels");
  }
  if (auto bad = unmappedIds(labeled.labels, label8Identity()); !bad.empty()) {
    throw Error("frame '" + labeled.name + "': label " + bad + " not a findmug id (0..7, 255)");
  }

  const fs::path root(dir);
  std::error_code ec;
  for (const char* sub : {"rgb", "depth", "label8"}) {
    fs::create_directories(root / sub, ec);
    if (ec) throw Error((root / sub).string() + ": cannot create (" + ec.message() + ")");
  }

  // One camera per folder: refuse to mix intrinsics silently.
  const fs::path intrinsics_path = root / "intrinsics.yaml";
  if (fs::exists(intrinsics_path, ec)) {
    const auto existing = readIntrinsicsYaml(intrinsics_path.string());
    const auto& k = frame.intrinsics;
    const auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); };
    if (!same(existing.fx, k.fx) || !same(existing.fy, k.fy) || !same(existing.cx, k.cx) ||
        !same(existing.cy, k.cy)) {
      std::ostringstream msg;
      msg << intrinsics_path.string() << ": frame '" << labeled.name
          << "' has different intrinsics (fx=" << k.fx << " fy=" << k.fy << " cx=" << k.cx
          << " cy=" << k.cy << ") than the folder (fx=" << existing.fx << " fy=" << existing.fy
          << " cx=" << existing.cx << " cy=" << existing.cy << ")";
      throw Error(msg.str());
    }
  } else {
    const auto& k = frame.intrinsics;
    writeTextFileAtomically(intrinsics_path,
                            "# Pinhole intrinsics of the colour camera (pixels), depth registered\n"
                            "fx: " +
                                formatDouble(k.fx) + "\nfy: " + formatDouble(k.fy) + "\ncx: " +
                                formatDouble(k.cx) + "\ncy: " + formatDouble(k.cy) + "\n");
  }

  const std::string png = labeled.name + ".png";
  writePngRgb((root / "rgb" / png).string(), Image<Rgb8>{frame.width, frame.height, frame.rgb});
  writePng16((root / "depth" / png).string(),
             Image<std::uint16_t>{frame.width, frame.height, frame.depth_mm});
  writePng8((root / "label8" / png).string(),
            Image<std::uint8_t>{frame.width, frame.height, labeled.labels});

  // extrinsics.csv: keep one row per frame; a rewritten frame replaces its
  // row, and a frame without extrinsics removes a stale one.
  const fs::path extrinsics_path = root / "extrinsics.csv";
  const bool exists = fs::exists(extrinsics_path, ec);
  if (!exists && !frame.extrinsics) return;
  std::vector<ExtrinsicsRow> rows;
  if (exists) rows = readExtrinsicsCsv(extrinsics_path.string());
  const auto old_size = rows.size();
  std::erase_if(rows, [&](const ExtrinsicsRow& r) { return r.name == labeled.name; });
  if (!frame.extrinsics && rows.size() == old_size) return;  // nothing to change
  if (frame.extrinsics) rows.push_back({labeled.name, *frame.extrinsics});
  std::string text = std::string(kExtrinsicsHeader) + "\n";
  for (const auto& r : rows) {
    text += r.name + "," + formatDouble(r.extrinsics.height_m) + "," +
            formatDouble(r.extrinsics.pitch_rad) + "," + formatDouble(r.extrinsics.roll_rad) + "\n";
  }
  writeTextFileAtomically(extrinsics_path, text);
}

}  // namespace findmug
