// Reader for the official NYU Depth V2 labelled set (nyu_depth_v2_labeled.mat).
//
// The file is MATLAB v7.3, i.e. HDF5. MATLAB stores arrays column-major and
// HDF5 reports dimensions row-major, so a MATLAB 480x640x3x1449 `images`
// appears here as [1449][3][640][480]: frame, channel, column x, row y, with
// y varying fastest. Every frame read here is transposed into our row-major
// (y * width + x) layout; getting that wrong gives a mirrored, rotated image
// that still "looks like" data, so the tests check exact pixel positions.
#include <hdf5.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/offline/nyu_mat.hpp"

namespace findmug {

namespace generated {
extern const char* const kDefaultDataDir;
}  // namespace generated

namespace {

// NYU-894 ids are 1..894; the table covers 0..kMaxNyu894Id (0 = unlabelled).
constexpr int kMaxNyu894Id = 65535;
// The largest frame accepted: NYU's are 640x480; 1280x1024 (Kinect-class
// high resolution) leaves room for other sensors in the same layout while
// keeping one frame's buffers (16 bytes a pixel here) near 20 MB, so that a
// forged header cannot make a load take seconds or hundreds of MB.
constexpr hsize_t kMaxMatWidth = 1280, kMaxMatHeight = 1024;

// Silences HDF5's automatic error-stack printing for a scope: we turn every
// failure into a findmug::Error instead of spraying the stack on stderr.
class QuietHdf5Errors {
 public:
  QuietHdf5Errors() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5Errors() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietHdf5Errors(const QuietHdf5Errors&) = delete;
  QuietHdf5Errors& operator=(const QuietHdf5Errors&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

// Owns one HDF5 identifier and closes it with the matching function.
class Hid {
 public:
  using Closer = herr_t (*)(hid_t);
  Hid() = default;
  Hid(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Hid() { reset(); }
  Hid(Hid&& other) noexcept : id_(other.id_), closer_(other.closer_) { other.id_ = -1; }
  Hid& operator=(Hid&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = other.id_;
      closer_ = other.closer_;
      other.id_ = -1;
    }
    return *this;
  }
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  void reset() {
    if (id_ >= 0 && closer_) closer_(id_);
    id_ = -1;
  }
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

struct DatasetInfo {
  Hid dataset;
  std::vector<hsize_t> dims;
  H5T_class_t type_class = H5T_NO_CLASS;
  std::size_t type_size = 0;
  H5T_sign_t sign = H5T_SGN_ERROR;
};

std::string dimsText(const std::vector<hsize_t>& dims) {
  std::string out = "[";
  for (std::size_t i = 0; i < dims.size(); ++i) {
    if (i) out += "][";
    out += std::to_string(dims[i]);
  }
  return out + "]";
}

std::string typeText(const DatasetInfo& info) {
  switch (info.type_class) {
    case H5T_INTEGER:
      return std::string(info.sign == H5T_SGN_NONE ? "uint" : "int") +
             std::to_string(8 * info.type_size);
    case H5T_FLOAT:
      return "float" + std::to_string(8 * info.type_size);
    default:
      return "HDF5 type class " + std::to_string(static_cast<int>(info.type_class));
  }
}

DatasetInfo openDataset(hid_t file, const std::string& path, const char* name) {
  DatasetInfo info;
  if (H5Lexists(file, name, H5P_DEFAULT) <= 0) {
    throw Error(path + ": missing dataset '" + name + "' (not an nyu_depth_v2_labeled.mat?)");
  }
  info.dataset = Hid(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!info.dataset.valid()) throw Error(path + ": cannot open dataset '" + name + "'");
  Hid space(H5Dget_space(info.dataset.get()), H5Sclose);
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space.get()) : -1;
  if (rank < 0) throw Error(path + ": cannot read the shape of '" + name + "'");
  info.dims.resize(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), info.dims.data(), nullptr);
  Hid type(H5Dget_type(info.dataset.get()), H5Tclose);
  if (!type.valid()) throw Error(path + ": cannot read the type of '" + name + "'");
  info.type_class = H5Tget_class(type.get());
  info.type_size = H5Tget_size(type.get());
  if (info.type_class == H5T_INTEGER) info.sign = H5Tget_sign(type.get());

  // Unchunked data must be stored whole. libhdf5 1.10 trusts the stored size of
  // a compact or contiguous dataset and copies its shape's worth of bytes from
  // a buffer of the stored size: a corrupt file read past the end of the heap
  // (found by fuzzing, tests/fuzz/regressions/nyu_mat).
  Hid create(H5Dget_create_plist(info.dataset.get()), H5Pclose);
  const H5D_layout_t layout = create.valid() ? H5Pget_layout(create.get()) : H5D_LAYOUT_ERROR;
  if (layout == H5D_LAYOUT_ERROR) {
    throw Error(path + ": cannot read the storage layout of '" + name + "'");
  }
  if (layout == H5D_COMPACT || layout == H5D_CONTIGUOUS) {
    hsize_t needed = info.type_size;
    for (const hsize_t d : info.dims) {
      if (__builtin_mul_overflow(needed, d, &needed)) {
        throw Error(path + ": dataset '" + name + "' of shape " + dimsText(info.dims) +
                    " is too large");
      }
    }
    const hsize_t stored = H5Dget_storage_size(info.dataset.get());
    if (stored < needed) {
      throw Error(path + ": dataset '" + name + "' stores " + std::to_string(stored) +
                  " bytes but its shape " + dimsText(info.dims) + " of " + typeText(info) +
                  " needs " + std::to_string(needed) + " (truncated or corrupt file)");
    }
  }
  return info;
}

void requireType(const std::string& path, const char* name, const DatasetInfo& info,
                 H5T_class_t type_class, std::size_t size, const char* expected) {
  const bool sign_ok = type_class != H5T_INTEGER || info.sign == H5T_SGN_NONE;
  if (info.type_class != type_class || info.type_size != size || !sign_ok) {
    throw Error(path + ": dataset '" + name + "' has type " + typeText(info) + ", expected " +
                expected);
  }
}

// Reads the hyperslab [index][...] of a dataset whose dims are
// [N][rest...] into `out` (native type `memory_type`).
void readFrameSlab(const std::string& path, const char* name, const DatasetInfo& info,
                   std::size_t index, hid_t memory_type, void* out) {
  Hid file_space(H5Dget_space(info.dataset.get()), H5Sclose);
  std::vector<hsize_t> start(info.dims.size(), 0), count(info.dims);
  start[0] = index;
  count[0] = 1;
  if (!file_space.valid() || H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(),
                                                 nullptr, count.data(), nullptr) < 0) {
    throw Error(path + ": cannot select frame " + std::to_string(index + 1) + " of '" + name + "'");
  }
  Hid memory_space(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr),
                   H5Sclose);
  if (!memory_space.valid() || H5Dread(info.dataset.get(), memory_type, memory_space.get(),
                                       file_space.get(), H5P_DEFAULT, out) < 0) {
    throw Error(path + ": cannot read frame " + std::to_string(index + 1) + " of '" + name +
                "' (truncated or corrupt file?)");
  }
}

// nyu894_id,name,nyu40_id,nyu40_name -> table indexed by the 894 id
// (-1 = not listed). Id 0 (unlabelled) maps to NYU-40's 0 (void).
std::vector<int> loadNyu894To40(const std::string& csv_path) {
  std::ifstream in(csv_path);
  if (!in) throw Error(csv_path + ": cannot open the NYU-894 -> 40 mapping");
  std::vector<int> table(kMaxNyu894Id + 1, -1);
  table[0] = 0;
  std::string line;
  int line_number = 0;
  bool header_seen = false;
  int entries = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const std::string where = csv_path + ":" + std::to_string(line_number);
    std::vector<std::string> fields;
    std::stringstream fields_in(line);
    for (std::string f; std::getline(fields_in, f, ',');) fields.push_back(f);
    if (!header_seen) {
      if (fields.size() < 3 || fields[0] != "nyu894_id" || fields[2] != "nyu40_id") {
        throw Error(where + ": expected header 'nyu894_id,name,nyu40_id,nyu40_name', found '" +
                    line + "'");
      }
      header_seen = true;
      continue;
    }
    if (fields.size() != 4) {
      throw Error(where + ": expected 4 fields, found " + std::to_string(fields.size()));
    }
    const long long id894 = parseInteger(fields[0]).value_or(-1);
    const bool id894_ok = id894 >= 1 && id894 <= kMaxNyu894Id;
    const long long id40 = parseInteger(fields[2]).value_or(-1);
    const bool id40_ok = id40 >= 1 && id40 <= 255;
    if (!id894_ok) throw Error(where + ": bad nyu894_id '" + fields[0] + "'");
    if (!id40_ok) throw Error(where + ": bad nyu40_id '" + fields[2] + "'");
    if (table[static_cast<std::size_t>(id894)] >= 0) {
      throw Error(where + ": duplicate nyu894_id " + std::to_string(id894));
    }
    table[static_cast<std::size_t>(id894)] = static_cast<int>(id40);
    ++entries;
  }
  if (entries == 0) throw Error(csv_path + ": no NYU-894 -> 40 entries");
  return table;
}

}  // namespace

std::string defaultNyu894To40CsvPath() {
  const char* env = std::getenv("FINDMUG_DATA");
  const std::string root = env && *env ? env : generated::kDefaultDataDir;
  return root + "/nyuv2_meta/nyu894_to_40.csv";
}

namespace {

// What the reader keeps of the file's structure.
struct MatStructure {
  Hid file;
  DatasetInfo images, depths, labels;
  std::size_t count = 0;
  int width = 0, height = 0;
};

// Opens the file and its three datasets and checks their types and shapes
// (everything the constructor reads of the file's structure).
void openStructure(const std::string& path, MatStructure& out) {
  QuietHdf5Errors quiet;
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    throw Error(path + ": not an HDF5 file (expected a MATLAB v7.3 .mat)");
  }
  out.file = Hid(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!out.file.valid()) throw Error(path + ": cannot open as HDF5");
  const hid_t file = out.file.get();
  out.images = openDataset(file, path, "images");
  out.depths = openDataset(file, path, "depths");
  out.labels = openDataset(file, path, "labels");
  requireType(path, "images", out.images, H5T_INTEGER, 1, "uint8");
  requireType(path, "depths", out.depths, H5T_FLOAT, 4, "float32 (metres)");
  requireType(path, "labels", out.labels, H5T_INTEGER, 2, "uint16 (NYU-894 ids)");

  const auto& im = out.images.dims;
  if (im.size() != 4 || im[1] != 3 || im[0] == 0 || im[2] == 0 || im[3] == 0) {
    throw Error(path + ": dataset 'images' has dims " + dimsText(im) +
                ", expected [N][3][width][height] (MATLAB height x width x 3 x N)");
  }
  if (im[2] > kMaxMatWidth || im[3] > kMaxMatHeight) {
    throw Error(path + ": dataset 'images' has dims " + dimsText(im) + ": frames of " +
                std::to_string(im[2]) + "x" + std::to_string(im[3]) + " exceed the " +
                std::to_string(kMaxMatWidth) + "x" + std::to_string(kMaxMatHeight) +
                " this reader accepts (NYU frames are 640x480)");
  }
  out.count = im[0];
  out.width = static_cast<int>(im[2]);
  out.height = static_cast<int>(im[3]);
  const std::vector<hsize_t> expected = {im[0], im[2], im[3]};
  for (const auto* d : {&out.depths, &out.labels}) {
    if (d->dims != expected) {
      throw Error(path + ": dataset '" + (d == &out.depths ? "depths" : "labels") +
                  "' has dims " + dimsText(d->dims) + ", expected " + dimsText(expected) +
                  " to match 'images' " + dimsText(im));
    }
  }
}

// libhdf5 1.10.8 (Debian 12) can crash on a corrupt file while it walks the
// file's structure, before it returns any error we could turn into one: a
// group's symbol-table lookup reading through a NULL buffer (SIGSEGV in
// H5F__accum_read under H5Lexists, found by fuzzing:
// tests/fuzz/regressions/nyu_mat/crash-7062bed8...). That is not ours to fix,
// but a training run given a damaged download must get an error naming the
// file, not a segmentation fault. So the structure is read once in a forked
// child: if libhdf5 kills the child, the file is refused here and never read
// in this process; if the child comes back (read or refused), this process
// does the same reads, which then go the same way. Costs one fork per file
// opened (a few ms); the readers are offline tools, never the daemon.
void openStructureInChild(const std::string& path) {
  std::fflush(nullptr);  // the child must not flush the parent's buffered output again
  const pid_t child = fork();
  if (child < 0) {
    throw Error(path + ": cannot start the process that checks the file with libhdf5: " +
                std::strerror(errno));
  }
  if (child == 0) {
    // A crash here must end this child quietly: no core file, and the signal
    // (not a sanitizer's or fuzzer's own report) is the answer.
    const rlimit no_core{0, 0};
    setrlimit(RLIMIT_CORE, &no_core);
    for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(sig, SIG_DFL);
    int code = 0;
    try {
      MatStructure scratch;
      openStructure(path, scratch);
    } catch (...) {
      code = 1;  // an ordinary refusal: the parent's own read gives the message
    }
    _exit(code);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0) {
    if (errno != EINTR) {
      throw Error(path + ": cannot wait for the process that checks the file with libhdf5: " +
                  std::strerror(errno));
    }
  }
  if (WIFSIGNALED(status)) {
    const char* name = sigabbrev_np(WTERMSIG(status));
    throw Error(path + ": corrupt HDF5 file: libhdf5 " + std::to_string(H5_VERS_MAJOR) + "." +
                std::to_string(H5_VERS_MINOR) + "." + std::to_string(H5_VERS_RELEASE) +
                " crashed reading its structure (SIG" + (name ? name : "?") +
                " in a child process), so it is not read");
  }
}

}  // namespace

struct NyuMatFile::Impl : MatStructure {
  std::string path;
  std::string mapping_path;
  std::vector<int> to40;  // NYU-894 id -> NYU-40 id, -1 = unknown
};

NyuMatFile::NyuMatFile(const std::string& path, const std::string& nyu894_to_40_csv)
    : impl_(new Impl) {
  try {
    impl_->path = path;
    impl_->mapping_path = nyu894_to_40_csv;
    impl_->to40 = loadNyu894To40(nyu894_to_40_csv);
    // Check the 40 -> 8 step now: every NYU-40 id the 894 table can produce
    // must be in the shipped mapping.
    for (int id : impl_->to40) {
      if (id >= 0 && defaultNyu40Mapping().to_findmug[static_cast<std::size_t>(id)] < 0) {
        throw Error(nyu894_to_40_csv + ": NYU-40 id " + std::to_string(id) + " is not in " +
                    defaultNyu40Mapping().source);
      }
    }

    {
      std::ifstream probe(path, std::ios::binary);
      if (!probe) throw Error(path + ": cannot open");
    }
    // libhdf5 first reads the file's structure in a child process: a corrupt
    // file can crash libhdf5 itself (see openStructureInChild).
    openStructureInChild(path);
    openStructure(path, *impl_);
  } catch (...) {
    delete impl_;
    throw;
  }
}

NyuMatFile::~NyuMatFile() { delete impl_; }

std::size_t NyuMatFile::size() const { return impl_->count; }

LabeledFrame NyuMatFile::load(std::size_t index0) const {
  const Impl& m = *impl_;
  if (index0 >= m.count) {
    throw Error(m.path + ": frame index " + std::to_string(index0) + " out of range (" +
                std::to_string(m.count) + " frames)");
  }
  const int w = m.width, h = m.height;
  const auto pixels = static_cast<std::size_t>(w) * h;
  std::vector<std::uint8_t> image(3 * pixels);
  std::vector<float> depth_m(pixels);
  std::vector<std::uint16_t> label894(pixels);
  {
    QuietHdf5Errors quiet;
    readFrameSlab(m.path, "images", m.images, index0, H5T_NATIVE_UINT8, image.data());
    readFrameSlab(m.path, "depths", m.depths, index0, H5T_NATIVE_FLOAT, depth_m.data());
    readFrameSlab(m.path, "labels", m.labels, index0, H5T_NATIVE_UINT16, label894.data());
  }

  LabeledFrame out;
  char name[32];
  std::snprintf(name, sizeof(name), "%04zu", index0 + 1);
  out.name = name;
  RgbdFrame& frame = out.frame;
  frame.width = w;
  frame.height = h;
  frame.intrinsics = kNyuIntrinsics;
  frame.seq = static_cast<std::int64_t>(index0 + 1);
  frame.source = m.path + " frame " + out.name;
  frame.rgb.resize(pixels);
  frame.depth_mm.resize(pixels);
  out.labels.resize(pixels);
  out.fine_labels.assign(pixels, 0);

  const auto& to8 = defaultNyu40Mapping().to_findmug;
  std::vector<std::size_t> unknown_counts;  // by NYU-894 id, only filled on error
  for (int x = 0; x < w; ++x) {
    for (int y = 0; y < h; ++y) {
      const std::size_t src = static_cast<std::size_t>(x) * h + y;  // [x][y], y fastest
      const std::size_t dst = static_cast<std::size_t>(y) * w + x;  // row-major
      frame.rgb[dst] = Rgb8{image[src], image[pixels + src], image[2 * pixels + src]};

      const float d = depth_m[src];
      if (!(d >= 0.0f) || d * 1000.0f > 65535.0f) {  // also catches NaN
        throw Error(frame.source + ": depth " + std::to_string(d) + " m at pixel (" +
                    std::to_string(x) + "," + std::to_string(y) +
                    ") is not a valid distance (0..65.535 m)");
      }
      frame.depth_mm[dst] = static_cast<std::uint16_t>(std::lround(d * 1000.0f));

      const int id40 = m.to40[label894[src]];
      if (id40 < 0) {
        if (unknown_counts.empty()) unknown_counts.assign(kMaxNyu894Id + 1, 0);
        ++unknown_counts[label894[src]];
        continue;
      }
      out.labels[dst] = static_cast<std::uint8_t>(to8[static_cast<std::size_t>(id40)]);
      if (out.labels[dst] != kVoidLabel && id40 <= kNyu40Classes)
        out.fine_labels[dst] = static_cast<std::uint8_t>(id40);
    }
  }
  if (!unknown_counts.empty()) {
    std::string ids;
    for (std::size_t id = 0; id < unknown_counts.size(); ++id) {
      if (unknown_counts[id] == 0) continue;
      if (!ids.empty()) ids += ", ";
      ids += "id " + std::to_string(id) + " (" + std::to_string(unknown_counts[id]) + " pixels)";
    }
    throw Error(frame.source + ": label " + ids + " not in " + m.mapping_path);
  }
  validateFrame(frame);
  return out;
}

}  // namespace findmug
