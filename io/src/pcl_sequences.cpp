// PCD / PCLZF / TIFF frame readers and the sequence sources built on them.
#include <pcl/io/lzf.h>
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

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
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
  if (size > 0 &&
      !in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
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

// Our own PCD reader: PCL's maps the file and, for binary_compressed data,
// trusts the stored compressed size — a truncated file makes it read past the
// end of the mapping. Here every size is checked against the bytes we have.
namespace {

struct PcdField {
  std::string name;
  int size = 0;
  char type = 0;
  int count = 1;
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::size_t width = 0, height = 0, points = 0;
  std::string data;
  std::size_t body_offset = 0;
};

std::size_t parseCount(const std::string& path, const std::string& key, const std::string& token) {
  std::size_t used = 0;
  long long v = -1;
  try {
    v = std::stoll(token, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != token.size() || v < 0)
    throw Error(path + ": PCD " + key + " '" + token + "' is not a count");
  return static_cast<std::size_t>(v);
}

PcdHeader parsePcdHeader(const std::string& path, const std::vector<std::uint8_t>& file) {
  PcdHeader h;
  std::vector<int> sizes, counts;
  std::vector<char> types;
  std::size_t pos = 0;
  while (h.data.empty()) {
    if (pos >= file.size() || pos > 4096) throw Error(path + ": PCD header has no DATA line");
    std::size_t eol = pos;
    while (eol < file.size() && file[eol] != '\n') ++eol;
    if (eol == file.size()) throw Error(path + ": PCD header has no DATA line");
    std::istringstream line(std::string(file.begin() + static_cast<std::ptrdiff_t>(pos),
                                        file.begin() + static_cast<std::ptrdiff_t>(eol)));
    pos = eol + 1;
    std::string key;
    if (!(line >> key) || key[0] == '#') continue;
    std::vector<std::string> tokens;
    for (std::string t; line >> t;) tokens.push_back(t);
    if (key == "FIELDS") {
      for (const auto& t : tokens) h.fields.push_back({t});
    } else if (key == "SIZE") {
      for (const auto& t : tokens) sizes.push_back(static_cast<int>(parseCount(path, key, t)));
    } else if (key == "TYPE") {
      for (const auto& t : tokens) types.push_back(t.size() == 1 ? t[0] : '?');
    } else if (key == "COUNT") {
      for (const auto& t : tokens) counts.push_back(static_cast<int>(parseCount(path, key, t)));
    } else if (key == "WIDTH" && tokens.size() == 1) {
      h.width = parseCount(path, key, tokens[0]);
    } else if (key == "HEIGHT" && tokens.size() == 1) {
      h.height = parseCount(path, key, tokens[0]);
    } else if (key == "POINTS" && tokens.size() == 1) {
      h.points = parseCount(path, key, tokens[0]);
    } else if (key == "DATA" && tokens.size() == 1) {
      h.data = tokens[0];
    }
  }
  h.body_offset = pos;
  if (counts.empty()) counts.assign(h.fields.size(), 1);
  if (h.fields.empty() || sizes.size() != h.fields.size() || types.size() != h.fields.size() ||
      counts.size() != h.fields.size()) {
    throw Error(path + ": PCD header FIELDS/SIZE/TYPE/COUNT disagree in length");
  }
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    h.fields[i].size = sizes[i];
    h.fields[i].type = types[i];
    h.fields[i].count = counts[i];
    if (sizes[i] < 1 || sizes[i] > 8 || counts[i] < 1 || counts[i] > 1024) {
      throw Error(path + ": PCD field " + h.fields[i].name + " has SIZE " +
                  std::to_string(sizes[i]) + " COUNT " + std::to_string(counts[i]));
    }
  }
  if (h.height <= 1 || h.width < 2 || h.width > static_cast<std::size_t>(kMaxSide) ||
      h.height > static_cast<std::size_t>(kMaxSide)) {
    throw Error(path + ": not an organized depth-camera cloud (" + std::to_string(h.width) + "x" +
                std::to_string(h.height) + ")");
  }
  if (h.points != h.width * h.height) {
    throw Error(path + ": PCD POINTS " + std::to_string(h.points) + " != WIDTH*HEIGHT");
  }
  return h;
}

}  // namespace

RgbdFrame readPcdFrame(const std::string& path) {
  const std::vector<std::uint8_t> file = readWholeFile(path);
  const PcdHeader h = parsePcdHeader(path, file);
  // Where x, y, z and rgb(a) live in a point (AoS) and in the field-major
  // layout of binary_compressed (SoA).
  int ix = -1, iy = -1, iz = -1, irgb = -1;
  std::vector<std::size_t> aos_offset(h.fields.size()), soa_offset(h.fields.size());
  std::size_t point_bytes = 0;
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    const auto& f = h.fields[i];
    aos_offset[i] = point_bytes;
    soa_offset[i] = point_bytes * h.points;
    point_bytes += static_cast<std::size_t>(f.size) * f.count;
    const int idx = static_cast<int>(i);
    if (f.name == "x") ix = idx;
    if (f.name == "y") iy = idx;
    if (f.name == "z") iz = idx;
    if (f.name == "rgb" || f.name == "rgba") irgb = idx;
  }
  if (ix < 0 || iy < 0 || iz < 0 || irgb < 0) {
    throw Error(path + ": PCD needs fields x y z and rgb or rgba");
  }
  for (int i : {ix, iy, iz}) {
    const auto& f = h.fields[static_cast<std::size_t>(i)];
    if (f.type != 'F' || f.size != 4 || f.count != 1) {
      throw Error(path + ": PCD field " + f.name + " must be one 4-byte float");
    }
  }
  if (h.fields[static_cast<std::size_t>(irgb)].size != 4 ||
      h.fields[static_cast<std::size_t>(irgb)].count != 1) {
    throw Error(path + ": PCD field rgb/rgba must be 4 bytes");
  }

  const std::size_t body_size = point_bytes * h.points;
  std::vector<std::uint8_t> decompressed;
  const std::uint8_t* body = nullptr;
  bool field_major = false;
  const std::size_t available = file.size() - h.body_offset;
  if (h.data == "binary") {
    if (available < body_size) {
      throw Error(path + ": PCD body has " + std::to_string(available) + " bytes, expected " +
                  std::to_string(body_size));
    }
    body = &file[h.body_offset];
  } else if (h.data == "binary_compressed") {
    if (available < 8) throw Error(path + ": PCD compressed body truncated");
    const std::uint32_t compressed = readLe32(&file[h.body_offset]);
    const std::uint32_t uncompressed = readLe32(&file[h.body_offset + 4]);
    if (uncompressed != body_size) {
      throw Error(path + ": PCD uncompressed size " + std::to_string(uncompressed) + ", expected " +
                  std::to_string(body_size));
    }
    if (compressed > available - 8) {
      throw Error(path + ": PCD compressed body of " + std::to_string(compressed) +
                  " bytes, only " + std::to_string(available - 8) + " in the file (truncated?)");
    }
    decompressed.resize(body_size);
    const unsigned int got =
        pcl::lzfDecompress(&file[h.body_offset + 8], compressed, decompressed.data(),
                           static_cast<unsigned int>(body_size));
    if (got != body_size) {
      throw Error(path + ": corrupt LZF data in PCD (" + std::to_string(got) + " of " +
                  std::to_string(body_size) + " bytes)");
    }
    body = decompressed.data();
    field_major = true;
  } else {
    throw Error(path + ": PCD DATA '" + h.data + "' not supported (binary, binary_compressed)");
  }
  auto fieldAt = [&](int field, std::size_t point) {
    const auto f = static_cast<std::size_t>(field);
    const std::uint8_t* p =
        field_major ? body + soa_offset[f] + point * 4 : body + point * point_bytes + aos_offset[f];
    std::uint32_t bits;
    std::memcpy(&bits, p, 4);  // PCD binary data is little-endian, as is the host
    return bits;
  };
  auto asFloat = [](std::uint32_t bits) {
    float v;
    std::memcpy(&v, &bits, 4);
    return v;
  };

  RgbdFrame frame;
  frame.width = static_cast<int>(h.width);
  frame.height = static_cast<int>(h.height);
  frame.source = path;
  frame.depth_mm.assign(h.points, 0);
  frame.rgb.resize(h.points);
  AxisAccumulator fit_u, fit_v;
  for (int v = 0; v < frame.height; ++v) {
    for (int u = 0; u < frame.width; ++u) {
      const auto i = static_cast<std::size_t>(v) * frame.width + u;
      const std::uint32_t rgb = fieldAt(irgb, i);
      frame.rgb[i] = Rgb8{static_cast<std::uint8_t>(rgb >> 16), static_cast<std::uint8_t>(rgb >> 8),
                          static_cast<std::uint8_t>(rgb)};
      const float x = asFloat(fieldAt(ix, i)), y = asFloat(fieldAt(iy, i)),
                  z = asFloat(fieldAt(iz, i));
      if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z)) || z <= 0.0f) continue;
      const double mm = std::round(static_cast<double>(z) * 1000.0);
      if (mm > 65535.0) {
        throw Error(path + ": point (" + std::to_string(u) + ", " + std::to_string(v) +
                    ") has z = " + std::to_string(z) + " m, beyond uint16 millimetres");
      }
      frame.depth_mm[i] = static_cast<std::uint16_t>(mm);
      fit_u.add(x / z, u);
      fit_v.add(y / z, v);
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
  if (value.empty()) throw Error(path + ": <" + tag + "> missing or not a number ('')");
  // XML may put white space around the text of an element.
  const auto first = value.find_first_not_of(" \t\n\r");
  const auto last = value.find_last_not_of(" \t\n\r");
  const auto v = first == std::string::npos
                     ? std::nullopt
                     : parseNumber(std::string_view(value).substr(first, last - first + 1));
  if (!v) throw Error(path + ": <" + tag + "> is not a number ('" + value + "')");
  return *v;
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
    throw Error(path + ": TIFF has " + std::to_string(spp) + " sample(s) of " +
                std::to_string(bps) + " bit(s) (format " + std::to_string(format) + "), expected " +
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
        out[(static_cast<std::size_t>(y) * w + x) * samples + s] =
            value;  // libtiff swabs to host order
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
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
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
          items.push_back(
              {stem, {path, need(stem, stem + "_rgb.pclzf"), need(stem, stem + ".xml")}});
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
  std::string description =
      spec.kind + ":" + spec.target + " (" + std::to_string(items->size()) + " frames";
  if (spec.options.rate_hz > 0)
    description += ", " + fmt::format("{:g}", spec.options.rate_hz) + " Hz";
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
      case PclFormat::Pcd:
        return readPcdFrame(item.files[0]);
      case PclFormat::Pclzf:
        return readPclzfFrame(item.files[0], item.files[1], item.files[2]);
      case PclFormat::Tiff:
        return readTiffFrame(item.files[0], item.files[1], tiff_k);
    }
    throw Error("unreachable");
  };
  return std::make_unique<FileSequenceSource>(std::move(description), items->size(),
                                              std::move(loader), spec.options);
}

}  // namespace detail
}  // namespace findmug::io
