// Taught object models (object_model.hpp): a view made from a table-top
// candidate, and the model file, written and read field by field with every
// field checked (a daemon reads these from a folder people copy files into).
#include "findmug/objects/object_model.hpp"

#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the object model file is little-endian and written from memory");

constexpr char kObjectModelMagic[8] = {'F', 'M', 'O', 'B', 'J', 'E', 'C', 'T'};
// A histogram (normalised to 1 when taught) may be off by float rounding only.
constexpr double kHistogramSumTolerance = 1e-3;
// Sizes and coordinates beyond this are no table-top object.
constexpr float kMaxObjectSizeM = 10.0f;

std::string formatValue(double v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

[[noreturn]] void badField(const std::string& what, const std::string& field,
                           const std::string& value, const std::string& rule) {
  throw Error("object model " + what + ": " + field + " = " + value + ": " + rule);
}

std::string viewField(int v, const char* field) {
  return "views[" + std::to_string(v) + "]." + field;
}

void checkSize(const std::string& what, const std::string& field, float v, bool allow_zero) {
  if (!std::isfinite(v) || v < 0.0f || (!allow_zero && v == 0.0f) || v > kMaxObjectSizeM) {
    badField(what, field, formatValue(v),
             std::string("must be a finite length in ") + (allow_zero ? "[0" : "(0") + ", " +
                 formatValue(kMaxObjectSizeM) + "] m");
  }
}

template <std::size_t N>
void checkHistogram(const std::string& what, const std::string& field,
                    const std::array<float, N>& h) {
  double sum = 0.0;
  for (std::size_t i = 0; i < N; ++i) {
    if (!std::isfinite(h[i]) || h[i] < 0.0f || h[i] > 1.0f) {
      badField(what, field + "[" + std::to_string(i) + "]", formatValue(h[i]),
               "must be a finite number in [0, 1]");
    }
    sum += h[i];
  }
  if (std::abs(sum - 1.0) > kHistogramSumTolerance) {
    badField(what, field, "sum " + formatValue(sum), "must sum to 1");
  }
}

void checkPoints(const std::string& what, int v, const ObjectView& view) {
  const auto n = view.points.size();
  if (n < static_cast<std::size_t>(kMinObjectViewPoints) ||
      n > static_cast<std::size_t>(kMaxObjectViewPoints)) {
    badField(what, viewField(v, "point_count"), std::to_string(n),
             "must be in [" + std::to_string(kMinObjectViewPoints) + ", " +
                 std::to_string(kMaxObjectViewPoints) + "]");
  }
  if (view.colors.size() != n) {
    badField(what, viewField(v, "colors"), std::to_string(view.colors.size()),
             "must hold one colour per point (" + std::to_string(n) + ")");
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      const float x = view.points[i][c];
      if (!std::isfinite(x) || std::abs(x) > kMaxObjectSizeM) {
        badField(what,
                 viewField(v, "points") + std::string("[") + std::to_string(i) + "]." + "xyz"[c],
                 formatValue(x), "must be finite, within " + formatValue(kMaxObjectSizeM) + " m");
      }
    }
  }
}

void checkView(const std::string& what, int v, const ObjectView& view) {
  checkSize(what, viewField(v, "height_above_top"), view.height_above_top, false);
  checkSize(what, viewField(v, "extents[0]"), view.extents.x(), false);
  checkSize(what, viewField(v, "extents[1]"), view.extents.y(), true);
  if (view.extents.y() > view.extents.x()) {
    badField(what, viewField(v, "extents[1]"), formatValue(view.extents.y()),
             "must be at most extents[0] (" + formatValue(view.extents.x()) + ")");
  }
  checkHistogram(what, viewField(v, "colour_histogram"), view.colour_histogram);
  checkHistogram(what, viewField(v, "shape"), view.shape);
  if (!std::isfinite(view.roundness) || view.roundness < 0.0f || view.roundness > kNotRound) {
    badField(what, viewField(v, "roundness"), formatValue(view.roundness),
             "must be a finite number in [0, " + formatValue(kNotRound) + "]");
  }
  checkPoints(what, v, view);
}

// ---------------------------------------------------------------- writing ----

class Writer {
 public:
  template <typename T>
  void put(const T& v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void putBytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    bytes_.insert(bytes_.end(), p, p + n);
  }
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  std::vector<std::uint8_t> bytes_;
};

void writeView(Writer& w, const ObjectView& view) {
  w.put(view.height_above_top);
  w.put(view.extents.x());
  w.put(view.extents.y());
  w.putBytes(view.colour_histogram.data(), sizeof(float) * kObjectColourBins);
  w.putBytes(view.shape.data(), sizeof(float) * kObjectShapeBins);
  w.put(view.roundness);
  w.put(static_cast<std::uint32_t>(view.points.size()));
  for (std::size_t i = 0; i < view.points.size(); ++i) {
    w.put(view.points[i].x());
    w.put(view.points[i].y());
    w.put(view.points[i].z());
    w.put(view.colors[i].r);
    w.put(view.colors[i].g);
    w.put(view.colors[i].b);
  }
}

// ---------------------------------------------------------------- reading ----

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size, const std::string& what)
      : data_(data), size_(size), what_(what) {}

  // Refuses to read past the end, naming the field being read.
  void need(std::size_t n, const std::string& field) const {
    if (size_ - pos_ < n) {
      throw Error("object model " + what_ + ": truncated at byte " + std::to_string(size_) +
                  " reading " + field + " (needs " + std::to_string(n) + " bytes at offset " +
                  std::to_string(pos_) + ")");
    }
  }
  template <typename T>
  T get(const std::string& field) {
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  void getBytes(void* out, std::size_t n, const std::string& field) {
    need(n, field);
    std::memcpy(out, data_ + pos_, n);
    pos_ += n;
  }
  std::size_t left() const { return size_ - pos_; }
  std::size_t pos() const { return pos_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  const std::string& what_;
};

constexpr std::size_t kPointBytes = 3 * sizeof(float) + 3;

// The version 1 file had no roundness: it is computed from the view's points.
constexpr std::uint32_t kFirstRoundnessVersion = 2;

std::uint32_t readHeader(Reader& r, const std::string& what) {
  char magic[sizeof(kObjectModelMagic)];
  r.getBytes(magic, sizeof(magic), "magic");
  if (std::memcmp(magic, kObjectModelMagic, sizeof(kObjectModelMagic)) != 0) {
    std::string shown;
    for (char c : magic) shown += (c >= 32 && c < 127) ? c : '?';
    badField(what, "magic", "\"" + shown + "\"", "must be \"FMOBJECT\" (not an object model)");
  }
  const auto version = r.get<std::uint32_t>("version");
  if (version < 1 || version > kObjectModelFormatVersion) {
    badField(what, "version", std::to_string(version),
             "unknown format version (this program reads 1 to " +
                 std::to_string(kObjectModelFormatVersion) + ")");
  }
  return version;
}

std::string readName(Reader& r, const std::string& what) {
  const auto length = r.get<std::uint32_t>("name_length");
  if (length < 1 || length > static_cast<std::uint32_t>(kMaxObjectNameLength)) {
    badField(what, "name_length", std::to_string(length),
             "must be in [1, " + std::to_string(kMaxObjectNameLength) + "]");
  }
  std::string name(length, '\0');
  r.getBytes(name.data(), length, "name");
  try {
    validateObjectModelName(name);
  } catch (const Error& e) {
    throw Error("object model " + what + ": " + e.what());
  }
  return name;
}

// Version 1 had no roundness, and its shape descriptor was ESF on all (up to
// 2000) points where version 2's is on kObjectShapePoints of them: both are
// computed from the stored points, so that old files match as new ones do.
void upgradeVersion1View(ObjectView& view, const std::string& what, int v) {
  view.roundness = objectRoundnessResidual(view.points);
  try {
    view.shape = objectShapeDescriptor(view.points);
  } catch (const Error& e) {
    badField(what, viewField(v, "points"), std::to_string(view.points.size()) + " points",
             std::string("version 1 view without a shape: ") + e.what());
  }
}

ObjectView readView(Reader& r, const std::string& what, int v, std::uint32_t version) {
  ObjectView view;
  view.height_above_top = r.get<float>(viewField(v, "height_above_top"));
  view.extents.x() = r.get<float>(viewField(v, "extents[0]"));
  view.extents.y() = r.get<float>(viewField(v, "extents[1]"));
  r.getBytes(view.colour_histogram.data(), sizeof(float) * kObjectColourBins,
             viewField(v, "colour_histogram"));
  r.getBytes(view.shape.data(), sizeof(float) * kObjectShapeBins, viewField(v, "shape"));
  if (version >= kFirstRoundnessVersion) view.roundness = r.get<float>(viewField(v, "roundness"));
  const auto count = r.get<std::uint32_t>(viewField(v, "point_count"));
  if (count < static_cast<std::uint32_t>(kMinObjectViewPoints) ||
      count > static_cast<std::uint32_t>(kMaxObjectViewPoints)) {
    badField(what, viewField(v, "point_count"), std::to_string(count),
             "must be in [" + std::to_string(kMinObjectViewPoints) + ", " +
                 std::to_string(kMaxObjectViewPoints) + "]");
  }
  // The bytes must be there before anything is allocated for them.
  const std::size_t n = count;
  r.need(n * kPointBytes, viewField(v, "points"));
  view.points.resize(n);
  view.colors.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::string field = viewField(v, "points");
    view.points[i].x() = r.get<float>(field);
    view.points[i].y() = r.get<float>(field);
    view.points[i].z() = r.get<float>(field);
    view.colors[i].r = r.get<std::uint8_t>(field);
    view.colors[i].g = r.get<std::uint8_t>(field);
    view.colors[i].b = r.get<std::uint8_t>(field);
  }
  if (version < kFirstRoundnessVersion) upgradeVersion1View(view, what, v);
  return view;
}

std::vector<std::uint8_t> readFileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("object model " + path + ": cannot open for reading");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
  if (in.bad()) throw Error("object model " + path + ": read error");
  return bytes;
}

}  // namespace

void validateObjectModelName(const std::string& name) {
  bool ok = !name.empty() && name.size() <= static_cast<std::size_t>(kMaxObjectNameLength);
  for (char c : name) {
    ok = ok && ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-');
  }
  if (!ok) {
    std::string shown;
    for (char c : name) shown += (c >= 32 && c < 127) ? c : '?';
    throw Error("name = \"" + shown + "\": must be 1 to " + std::to_string(kMaxObjectNameLength) +
                " of a-z, 0-9, '_' and '-'");
  }
}

void validateObjectModel(const ObjectModel& model, const std::string& what) {
  try {
    validateObjectModelName(model.name);
  } catch (const Error& e) {
    throw Error("object model " + what + ": " + e.what());
  }
  if (model.views.empty() || model.views.size() > static_cast<std::size_t>(kMaxObjectViews)) {
    badField(what, "view_count", std::to_string(model.views.size()),
             "must be in [1, " + std::to_string(kMaxObjectViews) + "]");
  }
  for (std::size_t v = 0; v < model.views.size(); ++v) {
    checkView(what, static_cast<int>(v), model.views[v]);
  }
}

void objectPointsOf(const OrganizedCloud& cloud, const std::vector<int>& pixels, int max_points,
                    std::vector<Eigen::Vector3f>& points, std::vector<Rgb8>& colors) {
  points.clear();
  colors.clear();
  std::vector<int> valid;
  valid.reserve(pixels.size());
  for (int p : pixels) {
    if (p < 0 || static_cast<std::size_t>(p) >= cloud.size()) {
      throw Error("object points: pixel " + std::to_string(p) + " outside the " +
                  std::to_string(cloud.width) + "x" + std::to_string(cloud.height) + " cloud");
    }
    if (cloud.points[p].allFinite()) valid.push_back(p);
  }
  // Evenly spread over the pixels: the k-th kept point is the
  // floor(k * n / m)-th valid one, so the subsample covers the whole object.
  const std::size_t n = valid.size();
  const std::size_t m = std::min<std::size_t>(n, static_cast<std::size_t>(std::max(max_points, 0)));
  points.reserve(m);
  colors.reserve(m);
  const bool has_colour = cloud.colors.size() == cloud.points.size();
  for (std::size_t k = 0; k < m; ++k) {
    const int p = valid[k * n / m];
    points.push_back(cloud.points[p]);
    colors.push_back(has_colour ? cloud.colors[p] : Rgb8{});
  }
}

ObjectView makeObjectView(const TableObject& candidate, std::vector<Eigen::Vector3f> points,
                          std::vector<Rgb8> colors) {
  if (colors.size() != points.size()) {
    throw Error("object view: " + std::to_string(points.size()) + " points but " +
                std::to_string(colors.size()) + " colours");
  }
  if (points.size() > static_cast<std::size_t>(kMaxObjectViewPoints)) {
    throw Error("object view: " + std::to_string(points.size()) + " points, at most " +
                std::to_string(kMaxObjectViewPoints) + " (objectPointsOf subsamples)");
  }
  ObjectView view;
  view.height_above_top = candidate.height_above_top;
  view.extents = Eigen::Vector2f(std::max(candidate.extents.x(), candidate.extents.y()),
                                 std::min(candidate.extents.x(), candidate.extents.y()));
  view.colour_histogram = candidate.colour_histogram;
  view.points = std::move(points);
  view.colors = std::move(colors);
  if (static_cast<int>(view.points.size()) < kMinObjectViewPoints) {
    throw Error("object view: the candidate has " + std::to_string(view.points.size()) +
                " points with depth, need " + std::to_string(kMinObjectViewPoints));
  }
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : view.points) centroid += p.cast<double>();
  centroid /= static_cast<double>(view.points.size());
  const Eigen::Vector3f c = centroid.cast<float>();
  for (auto& p : view.points) p -= c;
  view.shape = objectShapeDescriptor(view.points);
  view.roundness = objectRoundnessResidual(view.points);
  return view;
}

ObjectView makeObjectView(const OrganizedCloud& cloud_ground, const TableObject& candidate) {
  std::vector<Eigen::Vector3f> points;
  std::vector<Rgb8> colors;
  objectPointsOf(cloud_ground, candidate.pixels, kMaxObjectViewPoints, points, colors);
  return makeObjectView(candidate, std::move(points), std::move(colors));
}

int addObjectViewToFile(const std::string& path, const std::string& name, ObjectView view) {
  validateObjectModelName(name);
  ObjectModel model{name, {}};
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    model = loadObjectModel(path);
    if (model.name != name) {
      throw Error("object model " + path + ": holds \"" + model.name + "\", not \"" + name +
                  "\"");
    }
    if (model.views.size() >= static_cast<std::size_t>(kMaxObjectViews)) {
      throw Error("object model " + path + ": \"" + name + "\" already has " +
                  std::to_string(model.views.size()) + " views, the most a model may hold");
    }
  }
  model.views.push_back(std::move(view));
  saveObjectModel(path, model);
  return static_cast<int>(model.views.size());
}

std::vector<std::uint8_t> encodeObjectModel(const ObjectModel& model) {
  validateObjectModel(model, "\"" + model.name + "\" (being written)");
  Writer w;
  w.putBytes(kObjectModelMagic, sizeof(kObjectModelMagic));
  w.put(kObjectModelFormatVersion);
  w.put(static_cast<std::uint32_t>(model.name.size()));
  w.putBytes(model.name.data(), model.name.size());
  w.put(static_cast<std::uint32_t>(model.views.size()));
  for (const auto& view : model.views) writeView(w, view);
  return w.take();
}

ObjectModel decodeObjectModel(const std::uint8_t* data, std::size_t size, const std::string& what) {
  Reader r(data, size, what);
  const std::uint32_t version = readHeader(r, what);
  ObjectModel model;
  model.name = readName(r, what);
  const auto count = r.get<std::uint32_t>("view_count");
  if (count < 1 || count > static_cast<std::uint32_t>(kMaxObjectViews)) {
    badField(what, "view_count", std::to_string(count),
             "must be in [1, " + std::to_string(kMaxObjectViews) + "]");
  }
  for (std::uint32_t v = 0; v < count; ++v) {
    model.views.push_back(readView(r, what, static_cast<int>(v), version));
    checkView(what, static_cast<int>(v), model.views.back());
  }
  if (r.left() != 0) {
    badField(what, "trailing bytes", std::to_string(r.left()),
             "nothing may follow the last view (at offset " + std::to_string(r.pos()) + ")");
  }
  return model;
}

void saveObjectModel(const std::string& path, const ObjectModel& model) {
  const auto bytes = encodeObjectModel(model);
  // Same folder, so that the rename is atomic; the pid keeps two writers apart.
  const std::string tmp = path + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("object model " + path + ": cannot open " + tmp + " for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) {
      std::remove(tmp.c_str());
      throw Error("object model " + path + ": write error on " + tmp);
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw Error("object model " + path + ": cannot rename " + tmp + ": " + ec.message());
  }
}

ObjectModel loadObjectModel(const std::string& path) {
  const auto bytes = readFileBytes(path);
  return decodeObjectModel(bytes.data(), bytes.size(), path);
}

}  // namespace findmug
