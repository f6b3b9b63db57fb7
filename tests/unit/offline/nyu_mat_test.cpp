// Tests for NyuMatFile on small HDF5 files with the layout of the official
// nyu_depth_v2_labeled.mat (MATLAB v7.3), written here with the HDF5 C API.
//
// MATLAB is column-major: an image of H rows x W columns x 3 x N frames is
// seen by HDF5 as [N][3][W][H]. The test fills every array from a formula in
// (frame, channel, x, y) and checks that each pixel lands at (x, y) of our
// row-major frames, so a transposed or mirrored read fails.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/offline/nyu_mat.hpp"
#include "expect_error.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

namespace fs = std::filesystem;
using test::errorOf;
using test::TempDir;

constexpr int kW = 640, kH = 480;

// NYU-894 ids (checked against nyu894_to_40.csv) and what they become.
constexpr std::uint16_t kBook = 1;     // -> 40 otherprop -> object (7)
constexpr std::uint16_t kCeiling = 4;  // -> 22 ceiling   -> ceiling (3)
constexpr std::uint16_t kChair = 5;    // -> 5 chair      -> chair (5)
constexpr std::uint16_t kFloor = 11;   // -> 2 floor      -> floor (1)
constexpr std::uint16_t kTable = 19;   // -> 7 table      -> table (4)
constexpr std::uint16_t kWall = 21;    // -> 1 wall       -> wall (2)
constexpr std::uint16_t kBed = 157;    // -> 4 bed        -> unknown (0)

std::uint8_t colourAt(int n, int c, int x, int y) {
  return static_cast<std::uint8_t>((x * 3 + y * 7 + c * 50 + n * 11) & 0xFF);
}
float depthAt(int n, int x, int y) {
  if (x == 5 && y == 7) return 0.0f;  // a missing measurement
  return 0.5f + 0.004f * x + 0.01f * y + 0.1f * n;
}
// Regions by position so that a transposed read scrambles them.
std::uint16_t labelAt(int n, int x, int y) {
  if (y < 20) return 0;  // unlabelled strip at the top
  if (x < 50) return kWall;
  if (y > 400) return kFloor;
  if (x > 600) return kCeiling;
  if (y < 100) return n == 0 ? kTable : kChair;
  if (x < 300) return kBook;
  return kBed;
}

struct Layout {
  int frames = 3;
  bool with_images = true, with_depths = true, with_labels = true;
  hid_t depth_type = H5T_NATIVE_FLOAT;
  hid_t image_type = H5T_NATIVE_UINT8;
  bool labels_row_major = false;  // [N][H][W] instead of MATLAB's [N][W][H]
  std::function<void(int n, std::vector<float>&)> edit_depth;
  std::function<void(int n, std::vector<std::uint16_t>&)> edit_labels;
};

Layout frames(int n) {
  Layout layout;
  layout.frames = n;
  return layout;
}

void writeDataset(hid_t file, const char* name, hid_t file_type, hid_t mem_type,
                  const std::vector<hsize_t>& dims, const void* data) {
  const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  ASSERT_GE(space, 0);
  const hid_t set = H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(set, 0);
  ASSERT_GE(H5Dwrite(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), 0);
  H5Dclose(set);
  H5Sclose(space);
}

void writeMat(const std::string& path, const Layout& layout = {}) {
  const int N = layout.frames;
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const std::size_t plane = static_cast<std::size_t>(kW) * kH;
  if (layout.with_images) {
    std::vector<std::uint8_t> images(N * 3 * plane);
    for (int n = 0; n < N; ++n)
      for (int c = 0; c < 3; ++c)
        for (int x = 0; x < kW; ++x)
          for (int y = 0; y < kH; ++y)
            images[((static_cast<std::size_t>(n) * 3 + c) * kW + x) * kH + y] =
                colourAt(n, c, x, y);
    if (layout.image_type == H5T_NATIVE_UINT8) {
      writeDataset(file, "images", H5T_STD_U8LE, H5T_NATIVE_UINT8,
                   {hsize_t(N), 3, hsize_t(kW), hsize_t(kH)}, images.data());
    } else {
      std::vector<std::uint16_t> wide(images.begin(), images.end());
      writeDataset(file, "images", H5T_STD_U16LE, H5T_NATIVE_UINT16,
                   {hsize_t(N), 3, hsize_t(kW), hsize_t(kH)}, wide.data());
    }
  }
  if (layout.with_depths) {
    std::vector<float> depths(N * plane);
    for (int n = 0; n < N; ++n) {
      std::vector<float> frame(plane);
      for (int x = 0; x < kW; ++x)
        for (int y = 0; y < kH; ++y) frame[static_cast<std::size_t>(x) * kH + y] = depthAt(n, x, y);
      if (layout.edit_depth) layout.edit_depth(n, frame);
      std::copy(frame.begin(), frame.end(), depths.begin() + static_cast<long>(n * plane));
    }
    if (layout.depth_type == H5T_NATIVE_FLOAT) {
      writeDataset(file, "depths", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT,
                   {hsize_t(N), hsize_t(kW), hsize_t(kH)}, depths.data());
    } else {
      std::vector<double> wide(depths.begin(), depths.end());
      writeDataset(file, "depths", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                   {hsize_t(N), hsize_t(kW), hsize_t(kH)}, wide.data());
    }
  }
  if (layout.with_labels) {
    std::vector<std::uint16_t> labels(N * plane);
    for (int n = 0; n < N; ++n) {
      std::vector<std::uint16_t> frame(plane);
      for (int x = 0; x < kW; ++x)
        for (int y = 0; y < kH; ++y) frame[static_cast<std::size_t>(x) * kH + y] = labelAt(n, x, y);
      if (layout.edit_labels) layout.edit_labels(n, frame);
      std::copy(frame.begin(), frame.end(), labels.begin() + static_cast<long>(n * plane));
    }
    const std::vector<hsize_t> dims = layout.labels_row_major
                                          ? std::vector<hsize_t>{hsize_t(N), kH, kW}
                                          : std::vector<hsize_t>{hsize_t(N), kW, kH};
    writeDataset(file, "labels", H5T_STD_U16LE, H5T_NATIVE_UINT16, dims, labels.data());
  }
  H5Fclose(file);
}

std::uint8_t expectedLabel(int n, int x, int y) {
  switch (labelAt(n, x, y)) {
    case 0:
      return kVoidLabel;
    case kWall:
      return 2;
    case kFloor:
      return 1;
    case kCeiling:
      return 3;
    case kTable:
      return 4;
    case kChair:
      return 5;
    case kBook:
      return 7;
    case kBed:
      return 0;
  }
  return 254;
}

class NyuMat : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto csv = test::dataPath("nyuv2_meta/nyu894_to_40.csv");
    if (csv.empty()) {
      if (test::runningInCi()) FAIL() << "nyuv2_meta/nyu894_to_40.csv missing under CI=true";
      GTEST_SKIP() << "nyuv2_meta/nyu894_to_40.csv missing";
    }
    csv_ = csv.string();
  }
  std::string csv_;
  TempDir dir_;
};

TEST_F(NyuMat, PixelsLandAtTheRightPlaceAndLabelsMap894To40To8) {
  const auto path = dir_.str("nyu.mat");
  writeMat(path);
  NyuMatFile mat(path, csv_);
  ASSERT_EQ(mat.size(), 3u);
  for (int n : {0, 2}) {
    const auto f = mat.load(static_cast<std::size_t>(n));
    EXPECT_EQ(f.name, n == 0 ? "0001" : "0003");
    ASSERT_EQ(f.frame.width, kW);
    ASSERT_EQ(f.frame.height, kH);
    EXPECT_DOUBLE_EQ(f.frame.intrinsics.fx, kNyuIntrinsics.fx);
    EXPECT_FALSE(f.frame.extrinsics.has_value());
    std::size_t wrong_rgb = 0, wrong_depth = 0, wrong_label = 0, wrong_fine = 0;
    ASSERT_EQ(f.fine_labels.size(), f.labels.size());
    const auto& to8 = defaultNyu40Mapping().to_findmug;
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        const auto p = static_cast<std::size_t>(y) * kW + x;
        const Rgb8 want{colourAt(n, 0, x, y), colourAt(n, 1, x, y), colourAt(n, 2, x, y)};
        if (!(f.frame.rgb[p] == want)) ++wrong_rgb;
        const auto mm = static_cast<std::uint16_t>(std::lround(depthAt(n, x, y) * 1000.0f));
        if (f.frame.depth_mm[p] != mm) ++wrong_depth;
        if (f.labels[p] != expectedLabel(n, x, y)) ++wrong_label;
        // The NYU-40 class (training.split_labels) maps to the label; 0 where void.
        const int fine = f.fine_labels[p];
        if (f.labels[p] == kVoidLabel ? fine != 0 : (fine == 0 || to8[fine] != f.labels[p]))
          ++wrong_fine;
      }
    }
    EXPECT_EQ(wrong_fine, 0u) << "frame " << n;
    EXPECT_EQ(f.fine_labels[450 * kW + 320], 2);  // NYU-40 floor
    EXPECT_EQ(f.fine_labels[200 * kW + 10], 1);   // NYU-40 wall
    EXPECT_EQ(wrong_rgb, 0u) << "frame " << n;
    EXPECT_EQ(wrong_depth, 0u) << "frame " << n;
    EXPECT_EQ(wrong_label, 0u) << "frame " << n;
    // A few spelled-out pixels, so a failure says where things went.
    EXPECT_EQ(f.frame.rgb[10 * kW + 600].r, colourAt(n, 0, 600, 10));
    EXPECT_EQ(f.frame.depth_mm[7 * kW + 5], 0);  // missing stays missing
    EXPECT_EQ(f.frame.depth_mm[479 * kW + 639],
              static_cast<std::uint16_t>(std::lround(depthAt(n, 639, 479) * 1000.0f)));
    EXPECT_EQ(f.labels[0], kVoidLabel);
    EXPECT_EQ(f.labels[450 * kW + 320], 1);  // floor at the bottom
    EXPECT_EQ(f.labels[200 * kW + 10], 2);   // wall on the left
    EXPECT_EQ(f.labels[50 * kW + 400], n == 0 ? 4 : 5);
  }
  EXPECT_CONTAINS(errorOf([&] { mat.load(3); }), "out of range");
}

TEST_F(NyuMat, ConvertedFramesRoundTripThroughTheFolderLayout) {
  const auto path = dir_.str("nyu.mat");
  writeMat(path, frames(2));
  NyuMatFile mat(path, csv_);
  const auto f = mat.load(1);
  writeLabeledFrame(dir_.str("out"), f);
  DatasetOptions options;
  options.mask_nyu_border = false;
  const auto back = DatasetFolder(dir_.str("out"), options).load(0);
  EXPECT_EQ(back.name, "0002");
  EXPECT_EQ(back.labels, f.labels);
  EXPECT_EQ(back.frame.depth_mm, f.frame.depth_mm);
  EXPECT_EQ(back.frame.rgb, f.frame.rgb);
  EXPECT_DOUBLE_EQ(back.frame.intrinsics.cx, kNyuIntrinsics.cx);
}

TEST_F(NyuMat, MissingDatasetsAreNamed) {
  for (const char* missing : {"images", "depths", "labels"}) {
    Layout layout;
    layout.frames = 1;
    layout.with_images = std::string(missing) != "images";
    layout.with_depths = std::string(missing) != "depths";
    layout.with_labels = std::string(missing) != "labels";
    const auto path = dir_.str(std::string("no_") + missing + ".mat");
    writeMat(path, layout);
    const auto msg = errorOf([&] { NyuMatFile(path, csv_); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_CONTAINS(msg, std::string("missing dataset '") + missing + "'");
  }
}

TEST_F(NyuMat, WrongTypesAndDimsAreRejected) {
  Layout f64;
  f64.frames = 1;
  f64.depth_type = H5T_NATIVE_DOUBLE;
  writeMat(dir_.str("f64.mat"), f64);
  auto msg = errorOf([&] { NyuMatFile(dir_.str("f64.mat"), csv_); });
  EXPECT_CONTAINS(msg, "dataset 'depths' has type float64, expected float32");

  Layout u16;
  u16.frames = 1;
  u16.image_type = H5T_NATIVE_UINT16;
  writeMat(dir_.str("u16.mat"), u16);
  msg = errorOf([&] { NyuMatFile(dir_.str("u16.mat"), csv_); });
  EXPECT_CONTAINS(msg, "dataset 'images' has type uint16, expected uint8");

  // A header may claim frames of any size; past 1280x1024 it is refused
  // before anything is allocated for them (a forged 4096x4096 frame took
  // seconds and hundreds of MB to load).
  for (const auto& [w, h] : {std::pair<hsize_t, hsize_t>{1281, 2}, {2, 1025}}) {
    const auto path = dir_.str("big.mat");
    const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    std::vector<std::uint8_t> images(3 * w * h, 1);
    std::vector<float> depths(w * h, 1.0f);
    std::vector<std::uint16_t> labels(w * h, 0);
    writeDataset(file, "images", H5T_STD_U8LE, H5T_NATIVE_UINT8, {1, 3, w, h}, images.data());
    writeDataset(file, "depths", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {1, w, h}, depths.data());
    writeDataset(file, "labels", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, w, h}, labels.data());
    H5Fclose(file);
    msg = errorOf([&] { NyuMatFile(path, csv_); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_CONTAINS(msg, "exceed the 1280x1024 this reader accepts");
  }

  Layout swapped;
  swapped.frames = 1;
  swapped.labels_row_major = true;
  writeMat(dir_.str("swapped.mat"), swapped);
  msg = errorOf([&] { NyuMatFile(dir_.str("swapped.mat"), csv_); });
  EXPECT_CONTAINS(msg, "dataset 'labels' has dims [1][480][640], expected [1][640][480]");
}

TEST_F(NyuMat, BadFilesAreErrors) {
  auto msg = errorOf([&] { NyuMatFile(dir_.str("absent.mat"), csv_); });
  EXPECT_CONTAINS(msg, dir_.str("absent.mat"));

  {
    std::ofstream out(dir_.str("v5.mat"));
    out << "MATLAB 5.0 MAT-file, not HDF5";
  }
  msg = errorOf([&] { NyuMatFile(dir_.str("v5.mat"), csv_); });
  EXPECT_CONTAINS(msg, "not an HDF5 file");

  // Truncated: the header survives, the data does not.
  const auto path = dir_.str("cut.mat");
  writeMat(path, frames(2));
  fs::resize_file(path, fs::file_size(path) / 2);
  EXPECT_THROW(
      {
        NyuMatFile mat(path, csv_);
        for (std::size_t i = 0; i < mat.size(); ++i) mat.load(i);
      },
      Error);
}

// The .mat part of a fuzz input in tests/fuzz/regressions/nyu_mat, written to
// `mat_path`. The fuzz container: a 4-byte little-endian length, the CSV, then
// the .mat.
void writeMatOfFuzzInput(const std::string& input_name, const std::string& mat_path) {
  const auto input = test::sourceDir() / "tests/fuzz/regressions/nyu_mat" / input_name;
  std::ifstream in(input, std::ios::binary);
  ASSERT_TRUE(in) << input;
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GE(bytes.size(), 4u);
  std::size_t csv_size = 0;
  for (int k = 3; k >= 0; --k) csv_size = (csv_size << 8) | static_cast<unsigned char>(bytes[k]);
  csv_size = std::min(csv_size, bytes.size() - 4);
  std::ofstream out(mat_path, std::ios::binary);
  out << bytes.substr(4 + csv_size);
}

// A corrupt file found by fuzzing: a compact dataset that stores 8 bytes for a
// shape of hundreds. libhdf5 1.10 would copy the shape's worth from the 8-byte
// buffer (a heap overflow under ASan); the reader refuses the dataset first,
// naming it and both sizes.
TEST_F(NyuMat, DatasetStoringLessThanItsShapeIsRefusedBeforeReading) {
  const auto mat_path = dir_.str("overflow.mat");
  writeMatOfFuzzInput("crash-d911c150ed9f6977f0a6d33ad2b854aa870c2335", mat_path);
  const std::string msg = errorOf([&] {
    NyuMatFile mat(mat_path, csv_);
    for (std::size_t i = 0; i < mat.size(); ++i) mat.load(i);
  });
  EXPECT_CONTAINS(msg, mat_path);
  EXPECT_CONTAINS(msg, "bytes but its shape");
  EXPECT_CONTAINS(msg, "truncated or corrupt file");
}

// Another one, on which libhdf5 1.10.8 itself dies (SIGSEGV in a symbol-table
// lookup, before it could return an error): the reader tries the file's
// structure in a child process first, so this process gets an error naming the
// file and goes on (the next file opens as usual).
TEST_F(NyuMat, FileThatCrashesLibhdf5IsRefusedAndTheProcessGoesOn) {
  const auto mat_path = dir_.str("crashes_libhdf5.mat");
  writeMatOfFuzzInput("crash-7062bed8ee31805b61b429b3c7671b59f6125e5a", mat_path);
  const std::string msg = errorOf([&] { NyuMatFile mat(mat_path, csv_); });
  EXPECT_CONTAINS(msg, mat_path + ": corrupt HDF5 file: libhdf5 ");
  EXPECT_CONTAINS(msg, "crashed reading its structure (SIGSEGV in a child process)");

  Layout layout;
  layout.frames = 2;
  writeMat(dir_.str("good.mat"), layout);
  NyuMatFile good(dir_.str("good.mat"), csv_);
  EXPECT_EQ(good.size(), 2u);
  EXPECT_EQ(good.load(1).name, "0002");
}

TEST_F(NyuMat, UnknownLabelIdsAndBadDepthsAreReported) {
  Layout layout;
  layout.frames = 1;
  layout.edit_labels = [](int, std::vector<std::uint16_t>& labels) {
    labels[0] = 900;  // NYU-894 has ids 1..894
    labels[1] = 900;
    labels[2] = 5000;
  };
  writeMat(dir_.str("ids.mat"), layout);
  auto msg = errorOf([&] { NyuMatFile(dir_.str("ids.mat"), csv_).load(0); });
  EXPECT_CONTAINS(msg, dir_.str("ids.mat") + " frame 0001");
  EXPECT_CONTAINS(msg, "id 900 (2 pixels), id 5000 (1 pixels)");
  EXPECT_CONTAINS(msg, "nyu894_to_40.csv");

  Layout nan;
  nan.frames = 1;
  nan.edit_depth = [](int, std::vector<float>& d) { d[3 * kH + 4] = std::nanf(""); };
  writeMat(dir_.str("nan.mat"), nan);
  msg = errorOf([&] { NyuMatFile(dir_.str("nan.mat"), csv_).load(0); });
  EXPECT_CONTAINS(msg, "at pixel (3,4)");

  Layout far;
  far.frames = 1;
  far.edit_depth = [](int, std::vector<float>& d) { d[0] = 70.0f; };
  writeMat(dir_.str("far.mat"), far);
  msg = errorOf([&] { NyuMatFile(dir_.str("far.mat"), csv_).load(0); });
  EXPECT_CONTAINS(msg, "not a valid distance");
}

TEST_F(NyuMat, The894To40CsvIsReadAtRunTimeAndChecked) {
  const auto path = dir_.str("nyu.mat");
  writeMat(path, frames(1));
  // A custom table that sends "bed" (157) to NYU-40 chair (5).
  const auto custom = dir_.str("custom.csv");
  {
    std::ifstream in(csv_);
    std::ofstream out(custom);
    std::string line;
    while (std::getline(in, line)) {
      out << (line.rfind("157,", 0) == 0 ? "157,bed,5,chair" : line) << "\n";
    }
  }
  const auto f = NyuMatFile(path, custom).load(0);
  EXPECT_EQ(f.labels[300 * kW + 400], 5);  // was unknown with the official table

  auto msg = errorOf([&] { NyuMatFile(path, dir_.str("none.csv")); });
  EXPECT_CONTAINS(msg, dir_.str("none.csv"));
  {
    std::ofstream out(dir_.str("bad.csv"));
    out << "id,name\n1,book\n";
  }
  msg = errorOf([&] { NyuMatFile(path, dir_.str("bad.csv")); });
  EXPECT_CONTAINS(msg, "expected header 'nyu894_id,name,nyu40_id,nyu40_name'");
  {
    std::ofstream out(dir_.str("forty_one.csv"));
    out << "nyu894_id,nyu894_name,nyu40_id,nyu40_name\n1,book,41,nothing\n";
  }
  msg = errorOf([&] { NyuMatFile(path, dir_.str("forty_one.csv")); });
  EXPECT_CONTAINS(msg, "NYU-40 id 41 is not in");
}

TEST(NyuMatDefaults, CsvPathFollowsFindmugData) {
  const char* old = std::getenv("FINDMUG_DATA");
  const std::string saved = old ? old : "";
  setenv("FINDMUG_DATA", "/some/where", 1);
  EXPECT_EQ(defaultNyu894To40CsvPath(), "/some/where/nyuv2_meta/nyu894_to_40.csv");
  if (old) {
    setenv("FINDMUG_DATA", saved.c_str(), 1);
  } else {
    unsetenv("FINDMUG_DATA");
  }
  if (!old) {
    // The build-time default points at a folder that holds the table.
    EXPECT_NE(defaultNyu894To40CsvPath().find("nyuv2_meta/nyu894_to_40.csv"), std::string::npos);
  }
}

}  // namespace
}  // namespace findmug
