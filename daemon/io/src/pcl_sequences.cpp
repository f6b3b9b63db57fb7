// PCD / PCLZF / TIFF frame readers and the sequence sources built on them.
#include <pcl/io/lzf.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <spdlog/spdlog.h>
#include <tiffio.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "findmug/error.hpp"
#include "findmug/io/pcl_frames.hpp"
#include "sources_internal.hpp"

namespace fs = std::filesystem;

namespace findmug::io {

namespace {

constexpr int kMaxSide = 4096;

std::vector<std::uint8_t> readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::size_t>(in.tellg());
  in.seekg(0);
  std::vector<std::uint8_t> bytes(size);
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
    throw Error(path + ": read failed");
  }
  return bytes;
}

std::uint32_t readLe32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

// ---- PCD -------------------------------------------------------------------------------

// Least-squares fit of u = f * (x / z) + c over the valid pixels of one axis.
struct AxisFit {
  double f = 0.0, c = 0.0, rms = 0.0;
  std::size_t n = 0;
};

struct AxisAccumulator {
  double sa = 0, su = 0, saa = 0, sau = 0, suu = 0;
  std::size_t n = 0;
  void add(double a, double u) {
    sa += a;
    su += u;
    saa += a * a;
    sau += a * u;
    suu += u * u;
    ++n;
  }
  AxisFit solve() const {
    AxisFit fit;
    fit.n = n;
    const double det = n * saa - sa * sa;
    if (n < 2 || !(std::abs(det) > 1e-12)) return fit;
    fit.f = (n * sau - sa * su) / det;
    fit.c = (su - fit.f * sa) / n;
    // sum (u - f a - c)^2 expanded.
    const double sse = suu + fit.f * fit.f * saa + n * fit.c * fit.c - 2 * fit.f * sau -
                       2 * fit.c * su + 2 * fit.f * fit.c * sa;
    fit.rms = std::sqrt(std::max(0.0, sse / n));
    return fit;
  }
};

}  // namespace

RgbdFrame readPcdFrame(const std::string& path) {
  pcl::PCDReader reader;
  pcl::PCLPointCloud2 header;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, data_type = 0;
  unsigned int data_idx = 0;
  if (reader.readHeader(path, header, origin, orientation, version, data_type, data_idx) < 0) {
    throw Error(path + ": not a readable PCD header");
  }
  bool has_x = false, has_y = false, has_z = false, has_rgb = false;
  for (const auto& f : header.fields) {
    has_x |= f.name == "x";
    has_y |= f.name == "y";
    has_z |= f.name == "z";
    has_rgb |= f.name == "rgb" || f.name == "rgba";
  }
  if (!(has_x && has_y && has_z && has_rgb)) {
    throw Error(path + ": PCD needs fields x y z and rgb or rgba");
  }
  if (header.height <= 1 || header.width < 2 || header.width > kMaxSide ||
      header.height > kMaxSide) {
    throw Error(path + ": not an organized depth-camera cloud (" + std::to_string(header.width) +
                "x" + std::to_string(header.height) + ")");
  }
  pcl::PointCloud<pcl::PointXYZRGBA> cloud;
  int rc = -1;
  try {
    rc = reader.read(path, cloud);
  } catch (const std::exception& e) {
    throw Error(path + ": PCD read failed: " + e.what());
  }
  if (rc < 0) throw Error(path + ": PCD read failed (PCL code " + std::to_string(rc) + ")");
  if (cloud.width != header.width || cloud.height != header.height ||
      cloud.size() != static_cast<std::size_t>(cloud.width) * cloud.height) {
    throw Error(path + ": PCD body holds " + std::to_string(cloud.size()) + " points, header says " +
                std::to_string(header.width) + "x" + std::to_string(header.height));
  }

  RgbdFrame frame;
  frame.width = static_cast<int>(cloud.width);
  frame.height = static_cast<int>(cloud.height);
  frame.source = path;
  frame.depth_mm.assign(cloud.size(), 0);
  frame.rgb.resize(cloud.size());
  AxisAccumulator fit_u, fit_v;
  for (int v = 0; v < frame.height; ++v) {
    for (int u = 0; u < frame.width; ++u) {
      const auto i = static_cast<std::size_t>(v) * frame.width + u;
      const auto& p = cloud[i];
      frame.rgb[i] = Rgb8{p.r, p.g, p.b};
      if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) || p.z <= 0.0f) continue;
      const double mm = std::round(static_cast<double>(p.z) * 1000.0);
      if (mm > 65535.0) {
        throw Error(path + ": point (" + std::to_string(u) + ", " + std::to_string(v) +
                    ") has z = " + std::to_string(p.z) + " m, beyond uint16 millimetres");
      }
      frame.depth_mm[i] = static_cast<std::uint16_t>(mm);
      fit_u.add(p.x / p.z, u);
      fit_v.add(p.y / p.z, v);
    }
  }
  // PCD keeps no calibration, but an organized camera cloud is a pinhole
  // projection: x/z and y/z are affine in the pixel column / row.
  const AxisFit fu = fit_u.solve(), fv = fit_v.solve();
  if (fu.n < 100 || fu.f <= 0 || fv.f <= 0 || fu.rms > 0.5 || fv.rms > 0.5) {
    std::ostringstream msg;
    msg << path << ": cannot recover intrinsics: " << fu.n << " valid points, fit fx=" << fu.f
        << " (rms " << fu.rms << " px) fy=" << fv.f << " (rms " << fv.rms
        << " px); not a depth-camera cloud?";
    throw Error(msg.str());
  }
  frame.intrinsics = CameraIntrinsics{fu.f, fv.f, fu.c, fv.c};
  return frame;
}

// ---- PCLZF ------------------------------------------------------------------------------

namespace {

struct LzfImage {
  std::uint32_t width = 0, height = 0;
  std::string type;
  std::vector<std::uint8_t> data;  // decompressed
};

// PCLZF file: "PCLZF", uint32 width, uint32 height, char[16] type (space
// padded), uint32 compressed size, uint32 uncompressed size (little-endian),
// then the LZF block.
LzfImage readLzf(const std::string& path, const std::string& expected_type,
                 std::size_t bytes_per_pixel) {
  constexpr std::size_t kHeader = 5 + 4 + 4 + 16 + 4 + 4;
  const std::vector<std::uint8_t> file = readWholeFile(path);
  if (file.size() < kHeader || std::memcmp(file.data(), "PCLZF", 5) != 0) {
    throw Error(path + ": not a PCLZF file (" + std::to_string(file.size()) + " bytes)");
  }
  LzfImage image;
  image.width = readLe32(&file[5]);
  image.height = readLe32(&file[9]);
  image.type.assign(reinterpret_cast<const char*>(&file[13]), 16);
  image.type.erase(image.type.find_last_not_of(" \0", std::string::npos, 2) + 1);
  const std::uint32_t compressed = readLe32(&file[29]);
  const std::uint32_t uncompressed = readLe32(&file[33]);
  if (image.type != expected_type) {
    throw Error(path + ": image type '" + image.type + "', expected '" + expected_type + "'");
  }
  if (image.width < 1 || image.height < 1 || image.width > kMaxSide || image.height > kMaxSide) {
    throw Error(path + ": absurd size " + std::to_string(image.width) + "x" +
                std::to_string(image.height));
  }
  const std::size_t expected = std::size_t{image.width} * image.height * bytes_per_pixel;
  if (uncompressed != expected) {
    throw Error(path + ": uncompressed size field " + std::to_string(uncompressed) + ", expected " +
                std::to_string(expected) + " for " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + " " + expected_type);
  }
  if (compressed != file.size() - kHeader) {
    throw Error(path + ": compressed size field " + std::to_string(compressed) + " but " +
                std::to_string(file.size() - kHeader) + " bytes follow the header");
  }
  image.data.resize(expected);
  const unsigned int got = pcl::lzfDecompress(&file[kHeader], compressed, image.data.data(),
                                              static_cast<unsigned int>(expected));
  if (got != expected) {
    throw Error(path + ": corrupt LZF data (" + std::to_string(got) + " of " +
                std::to_string(expected) + " bytes decompressed)");
  }
  return image;
}

// Text of <tag>...</tag> inside `text`, or empty.
std::string xmlValue(const std::string& text, const std::string& tag) {
  const std::string open = "<" + tag + ">", close = "</" + tag + ">";
  const auto a = text.find(open);
  if (a == std::string::npos) return {};
  const auto b = text.find(close, a + open.size());
  if (b == std::string::npos) return {};
  return text.substr(a + open.size(), b - a - open.size());
}

double xmlNumber(const std::string& section, const std::string& tag, const std::string& path) {
  const std::string value = xmlValue(section, tag);
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || end == value.c_str() || !std::isfinite(v)) {
    throw Error(path + ": <" + tag + "> missing or not a number ('" + value + "')");
  }
  while (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r') ++end;
  if (*end != '\0') throw Error(path + ": <" + tag + "> is not a number ('" + value + "')");
  return v;
}

}  // namespace

RgbdFrame readPclzfFrame(const std::string& depth_path, const std::string& rgb_path,
                         const std::string& xml_path) {
  const std::vector<std::uint8_t> xml_bytes = readWholeFile(xml_path);
  const std::string xml(xml_bytes.begin(), xml_bytes.end());
  const std::string depth_section = xmlValue(xml, "depth");
  if (depth_section.empty()) throw Error(xml_path + ": no <depth> section");
  CameraIntrinsics k{xmlNumber(depth_section, "focal_length_x", xml_path),
                     xmlNumber(depth_section, "focal_length_y", xml_path),
                     xmlNumber(depth_section, "principal_point_x", xml_path),
                     xmlNumber(depth_section, "principal_point_y", xml_path)};
  const double z_factor = xmlNumber(depth_section, "z_multiplication_factor", xml_path);
  if (!(z_factor > 0.0 && z_factor <= 1.0)) {
    throw Error(xml_path + ": z_multiplication_factor " + std::to_string(z_factor) +
                " outside (0, 1] metres per unit");
  }
  const double mm_per_unit = z_factor * 1000.0;

  const LzfImage depth = readLzf(depth_path, "depth16", 2);
  const LzfImage rgb = readLzf(rgb_path, "rgb24", 3);
  if (depth.width != rgb.width || depth.height != rgb.height) {
    throw Error(depth_path + ": depth is " + std::to_string(depth.width) + "x" +
                std::to_string(depth.height) + " but " + rgb_path + " is " +
                std::to_string(rgb.width) + "x" + std::to_string(rgb.height));
  }
  RgbdFrame frame;
  frame.width = static_cast<int>(depth.width);
  frame.height = static_cast<int>(depth.height);
  frame.source = depth_path;
  frame.intrinsics = k;
  const std::size_t pixels = static_cast<std::size_t>(frame.width) * frame.height;
  frame.depth_mm.resize(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint16_t raw =
        static_cast<std::uint16_t>(depth.data[2 * i] | (depth.data[2 * i + 1] << 8));
    const double mm = std::round(raw * mm_per_unit);
    if (mm > 65535.0) throw Error(depth_path + ": depth value beyond uint16 millimetres");
    frame.depth_mm[i] = static_cast<std::uint16_t>(mm);
  }
  // PCL's writer stores rgb24 planar (all R, then all G, then all B): it
  // compresses better than interleaved.
  frame.rgb.resize(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    frame.rgb[i] = Rgb8{rgb.data[i], rgb.data[pixels + i], rgb.data[2 * pixels + i]};
  }
  return frame;
}

// ---- TIFF ---------------------------------------------------------------------------------

namespace {

thread_local std::string tiff_last_error;

void tiffErrorHandler(const char* module, const char* fmt, va_list args) {
  char buffer[512];
  std::vsnprintf(buffer, sizeof(buffer), fmt, args);
  tiff_last_error = std::string(module ? module : "") + (module ? ": " : "") + buffer;
}

void installTiffHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    TIFFSetErrorHandler(tiffErrorHandler);
    TIFFSetWarningHandler(nullptr);  // unknown private tags are common and harmless
  });
}

struct TiffCloser {
  void operator()(TIFF* t) const { TIFFClose(t); }
};

// Reads a stripped, contiguous TIFF with `samples` samples of `bits` bits.
template <typename T>
std::vector<T> readTiff(const std::string& path, int samples, int bits, int& width, int& height) {
  installTiffHandlers();
  tiff_last_error.clear();
  std::unique_ptr<TIFF, TiffCloser> tif(TIFFOpen(path.c_str(), "r"));
  if (!tif) throw Error(path + ": cannot open TIFF: " + tiff_last_error);
  std::uint32_t w = 0, h = 0;
  std::uint16_t bps = 0, spp = 1, planar = PLANARCONFIG_CONTIG, format = SAMPLEFORMAT_UINT;
  TIFFGetField(tif.get(), TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetField(tif.get(), TIFFTAG_IMAGELENGTH, &h);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_BITSPERSAMPLE, &bps);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLEFORMAT, &format);
  if (w < 1 || h < 1 || w > kMaxSide || h > kMaxSide) {
    throw Error(path + ": absurd TIFF size " + std::to_string(w) + "x" + std::to_string(h));
  }
  const bool rgba_ok = samples == 3 && spp == 4;  // RGBA: alpha dropped
  if (bps != bits || (spp != samples && !rgba_ok) || format != SAMPLEFORMAT_UINT) {
    throw Error(path + ": TIFF has " + std::to_string(spp) + " sample(s) of " + std::to_string(bps) +
                " bit(s) (format " + std::to_string(format) + "), expected " +
                std::to_string(samples) + " unsigned of " + std::to_string(bits));
  }
  if (TIFFIsTiled(tif.get()) || (spp > 1 && planar != PLANARCONFIG_CONTIG)) {
    throw Error(path + ": tiled or planar TIFF not supported");
  }
  const std::size_t row_bytes = static_cast<std::size_t>(w) * spp * (bits / 8);
  if (static_cast<std::size_t>(TIFFScanlineSize(tif.get())) != row_bytes) {
    throw Error(path + ": unexpected TIFF scanline size " +
                std::to_string(TIFFScanlineSize(tif.get())));
  }
  std::vector<std::uint8_t> row(row_bytes);
  std::vector<T> out(static_cast<std::size_t>(w) * h * samples);
  for (std::uint32_t y = 0; y < h; ++y) {
    if (TIFFReadScanline(tif.get(), row.data(), y, 0) < 0) {
      throw Error(path + ": TIFF row " + std::to_string(y) + " unreadable: " + tiff_last_error);
    }
    for (std::uint32_t x = 0; x < w; ++x) {
      for (int s = 0; s < samples; ++s) {
        T value;
        std::memcpy(&value, &row[(static_cast<std::size_t>(x) * spp + s) * sizeof(T)], sizeof(T));
        out[(static_cast<std::size_t>(y) * w + x) * samples + s] = value;  // libtiff swabs to host order
      }
    }
  }
  width = static_cast<int>(w);
  height = static_cast<int>(h);
  return out;
}

}  // namespace

RgbdFrame readTiffFrame(const std::string& depth_path, const std::string& rgb_path,
                        const CameraIntrinsics& intrinsics) {
  RgbdFrame frame;
  int dw = 0, dh = 0, cw = 0, ch = 0;
  frame.depth_mm = readTiff<std::uint16_t>(depth_path, 1, 16, dw, dh);
  const std::vector<std::uint8_t> rgb = readTiff<std::uint8_t>(rgb_path, 3, 8, cw, ch);
  if (dw != cw || dh != ch) {
    throw Error(depth_path + ": depth is " + std::to_string(dw) + "x" + std::to_string(dh) +
                " but " + rgb_path + " is " + std::to_string(cw) + "x" + std::to_string(ch));
  }
  frame.width = dw;
  frame.height = dh;
  frame.source = depth_path;
  frame.intrinsics = intrinsics;
  frame.rgb.resize(frame.depth_mm.size());
  for (std::size_t i = 0; i < frame.rgb.size(); ++i) {
    frame.rgb[i] = Rgb8{rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]};
  }
  return frame;
}

// ---- sequences ------------------------------------------------------------------------------

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::vector<PclSequenceItem> listPclSequence(const std::string& dir, PclFormat format) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error(dir + ": not a directory");
  std::map<std::string, std::string> files;  // file name -> path, sorted
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) files[entry.path().filename().string()] = entry.path().string();
  }
  std::vector<PclSequenceItem> items;
  const auto need = [&](const std::string& stem, const std::string& name) {
    const auto it = files.find(name);
    if (it == files.end()) throw Error(dir + ": frame " + stem + " has no " + name);
    return it->second;
  };
  for (const auto& [name, path] : files) {
    switch (format) {
      case PclFormat::Pcd:
        if (endsWith(name, ".pcd")) items.push_back({name.substr(0, name.size() - 4), {path}});
        break;
      case PclFormat::Pclzf:
        if (endsWith(name, "_depth.pclzf")) {
          const std::string stem = name.substr(0, name.size() - 12);
          items.push_back({stem, {path, need(stem, stem + "_rgb.pclzf"), need(stem, stem + ".xml")}});
        }
        break;
      case PclFormat::Tiff:
        for (const char* ext : {".tiff", ".tif"}) {
          const std::string depth_suffix = std::string("_depth") + ext;
          if (endsWith(name, depth_suffix)) {
            const std::string stem = name.substr(0, name.size() - depth_suffix.size());
            items.push_back({stem, {path, need(stem, stem + "_rgb" + ext)}});
          }
        }
        break;
    }
  }
  if (items.empty()) throw Error(dir + ": no frames of the requested format");
  return items;
}

namespace detail {

std::unique_ptr<FrameSource> makePclSequenceSource(const SourceSpec& spec) {
  const PclFormat format = spec.kind == "pcd"     ? PclFormat::Pcd
                           : spec.kind == "pclzf" ? PclFormat::Pclzf
                                                  : PclFormat::Tiff;
  auto items = std::make_shared<std::vector<PclSequenceItem>>(listPclSequence(spec.target, format));
  std::string description = spec.kind + ":" + spec.target + " (" + std::to_string(items->size()) +
                            " frames";
  if (spec.options.rate_hz > 0) description += ", " + fmt::format("{:g}", spec.options.rate_hz) + " Hz";
  if (spec.options.loop) description += ", loop";
  description += ")";
  // TIFF files carry no calibration: the Kinect-class default unless configured.
  const CameraIntrinsics tiff_k = spec.options.intrinsics.value_or(CameraIntrinsics{});
  if (format == PclFormat::Tiff && !spec.options.intrinsics) {
    spdlog::info("{}: TIFF has no calibration; using fx={} fy={} cx={} cy={}", description,
                 tiff_k.fx, tiff_k.fy, tiff_k.cx, tiff_k.cy);
  }
  auto loader = [items, format, tiff_k](std::size_t i) {
    const PclSequenceItem& item = (*items)[i];
    switch (format) {
      case PclFormat::Pcd: return readPcdFrame(item.files[0]);
      case PclFormat::Pclzf: return readPclzfFrame(item.files[0], item.files[1], item.files[2]);
      case PclFormat::Tiff: return readTiffFrame(item.files[0], item.files[1], tiff_k);
    }
    throw Error("unreachable");
  };
  return std::make_unique<FileSequenceSource>(std::move(description), items->size(),
                                              std::move(loader), spec.options);
}

}  // namespace detail
}  // namespace findmug::io
