// semantic_map.cpp — label votes fused in a hashed voxel grid (see semantic_map.hpp).
#include "findmug/map/semantic_map.hpp"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/settings/config.hpp"

namespace findmug {

namespace {

static_assert(std::endian::native == std::endian::little,
              "the semantic map file is written in the host's (little-endian) byte order");

constexpr double kPi = 3.14159265358979323846;
constexpr int kKeyBits = 21;
constexpr std::int64_t kKeyOffset = std::int64_t{1} << (kKeyBits - 1);
constexpr std::uint64_t kKeyMask = (std::uint64_t{1} << kKeyBits) - 1;
constexpr double kMaxPoseDistanceM = 10000.0;
constexpr char kMagic[16] = {'F', 'I', 'N', 'D', 'M', 'U', 'G', '-',
                             'S', 'E', 'M', 'M', 'A', 'P', '\0', '\n'};

std::string fmt(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

[[noreturn]] void badSetting(const std::string& key, double value, const std::string& rule) {
  throw Error("semantic_map." + key + " = " + fmt(value) + ": " + rule);
}

std::uint64_t packIndices(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (static_cast<std::uint64_t>(x + kKeyOffset) << (2 * kKeyBits)) |
         (static_cast<std::uint64_t>(y + kKeyOffset) << kKeyBits) |
         static_cast<std::uint64_t>(z + kKeyOffset);
}

Eigen::Array3i unpackIndices(std::uint64_t key) {
  return Eigen::Array3i(
      static_cast<int>(static_cast<std::int64_t>((key >> (2 * kKeyBits)) & kKeyMask) - kKeyOffset),
      static_cast<int>(static_cast<std::int64_t>((key >> kKeyBits) & kKeyMask) - kKeyOffset),
      static_cast<int>(static_cast<std::int64_t>(key & kKeyMask) - kKeyOffset));
}

// The floor cell (voxel column) of a voxel key: its x and y indices, z = 0.
std::uint64_t columnOf(std::uint64_t key) {
  return (key & ~kKeyMask) | static_cast<std::uint64_t>(kKeyOffset);
}

bool insideConvexOrNear(const Eigen::Vector2f& p, const std::vector<Eigen::Vector2f>& hull,
                        float margin) {
  if (hull.size() < 3) return false;
  bool inside = true;
  float nearest = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2f& a = hull[i];
    const Eigen::Vector2f& b = hull[(i + 1) % hull.size()];
    const Eigen::Vector2f ab = b - a, ap = p - a;
    if (ab.x() * ap.y() - ab.y() * ap.x() < 0.0f) inside = false;
    const float len2 = ab.squaredNorm();
    const float t = len2 > 0.0f ? std::clamp(ap.dot(ab) / len2, 0.0f, 1.0f) : 0.0f;
    nearest = std::min(nearest, (a + t * ab - p).norm());
  }
  return inside || nearest <= margin;
}

// Adds `vote` to one label of a voxel; halves all its votes first when the count would
// overflow its 16 bits.
void addVote(SemanticMap::Voxel& voxel, int label, int vote) {
  while (voxel.votes[label] + vote > 0xFFFF) {
    for (auto& v : voxel.votes) v = static_cast<std::uint16_t>(v / 2);
  }
  voxel.votes[label] = static_cast<std::uint16_t>(voxel.votes[label] + vote);
}

// One sampled pixel of a frame, for grouping by voxel.
struct Hit {
  std::uint64_t key;
  std::uint8_t label;
  float confidence;
};

// ---- binary writing and reading ----------------------------------------------------------

class Writer {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  std::vector<std::uint8_t> bytes;
};

class Reader {
 public:
  Reader(const std::vector<std::uint8_t>& bytes, std::size_t end, std::string path)
      : bytes_(bytes), end_(end), path_(std::move(path)) {}

  template <class T>
  T get(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (end_ - pos_ < sizeof(T)) fail(std::string("truncated while reading ") + what);
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  // A count of items of `item_bytes` each: refused when the bytes left cannot hold them.
  std::uint64_t count(std::uint64_t n, std::size_t item_bytes, const char* what) {
    if (n > (end_ - pos_) / item_bytes) {
      fail(std::string("claims ") + std::to_string(n) + " " + what + " but only " +
           std::to_string(end_ - pos_) + " bytes follow");
    }
    return n;
  }
  bool atEnd() const { return pos_ == end_; }
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error("semantic map " + path_ + ": " + problem);
  }

 private:
  const std::vector<std::uint8_t>& bytes_;
  std::size_t end_;
  std::size_t pos_ = 0;
  std::string path_;
};

}  // namespace

// ---- settings ------------------------------------------------------------------------------

void validateSemanticMapConfig(const SemanticMapConfig& c) {
  auto positive = [](const char* key, float v) {
    if (!std::isfinite(v) || v <= 0.0f) badSetting(key, v, "must be a positive number");
  };
  if (!std::isfinite(c.voxel_size_m) || c.voxel_size_m < 0.01f || c.voxel_size_m > 1.0f) {
    badSetting("voxel_size_m", c.voxel_size_m, "must be in [0.01, 1] m");
  }
  if (c.pixel_stride < 1 || c.pixel_stride > 16) {
    badSetting("pixel_stride", c.pixel_stride, "must be in [1, 16]");
  }
  if (c.carve_stride < 1 || c.carve_stride > 64) {
    badSetting("carve_stride", c.carve_stride, "must be in [1, 64]");
  }
  positive("max_range_m", c.max_range_m);
  if (c.max_range_m > 100.0f) badSetting("max_range_m", c.max_range_m, "must be at most 100 m");
  if (!std::isfinite(c.carve_margin_m) || c.carve_margin_m < 0.0f) {
    badSetting("carve_margin_m", c.carve_margin_m, "must be a number >= 0");
  }
  positive("hit_logodds", c.hit_logodds);
  positive("miss_logodds", c.miss_logodds);
  positive("max_logodds", c.max_logodds);
  if (!std::isfinite(c.seen_through_logodds) || c.seen_through_logodds < 0.0f ||
      c.seen_through_logodds > 125.0f) {
    badSetting("seen_through_logodds", c.seen_through_logodds, "must be in [0, 125] (0: off)");
  }
  if (c.max_logodds * SemanticMap::kLogOddsScale > 32000.0f) {
    badSetting("max_logodds", c.max_logodds, "must be at most 125");
  }
  if (c.hit_logodds > c.max_logodds) {
    badSetting("hit_logodds", c.hit_logodds,
               "must not be above semantic_map.max_logodds (" + fmt(c.max_logodds) + ")");
  }
  if (c.max_voxels < 1000) badSetting("max_voxels", c.max_voxels, "must be >= 1000");
  if (c.min_table_voxels < 1) badSetting("min_table_voxels", c.min_table_voxels, "must be >= 1");
  if (c.min_voxel_frames < 1) badSetting("min_voxel_frames", c.min_voxel_frames, "must be >= 1");
  if (!std::isfinite(c.table_match_gap_m) || c.table_match_gap_m < 0.0f) {
    badSetting("table_match_gap_m", c.table_match_gap_m, "must be a number >= 0");
  }
  if (c.support_frames < 1) badSetting("support_frames", c.support_frames, "must be >= 1");
  if (c.support_min_voxels < 1) {
    badSetting("support_min_voxels", c.support_min_voxels, "must be >= 1");
  }
  positive("viewpoint_cell_m", c.viewpoint_cell_m);
  if (!std::isfinite(c.viewpoint_angle_deg) || c.viewpoint_angle_deg <= 0.0f ||
      c.viewpoint_angle_deg > 360.0f) {
    badSetting("viewpoint_angle_deg", c.viewpoint_angle_deg, "must be in (0, 360]");
  }
}

const SettingsTable<SemanticMapConfig>& semanticMapSettings() {
  using M = SemanticMapConfig;
  static const SettingsTable<M> table = [] {
    SettingsTable<M> t("semantic_map");
    t.add(numberSetting<M, float>(
        "semantic_map.voxel_size_m", [](M& m) -> float& { return m.voxel_size_m; }, 0.01, 1,
        "edge of a map voxel"));
    t.add(integerSetting<M, int>(
        "semantic_map.pixel_stride", [](M& m) -> int& { return m.pixel_stride; }, 1, 16,
        "every n-th pixel of every n-th row is fused"));
    t.add(integerSetting<M, int>(
        "semantic_map.carve_stride", [](M& m) -> int& { return m.carve_stride; }, 1, 64,
        "every n-th pixel of every n-th row casts a free-space ray"));
    t.add(numberSetting<M, float>(
        "semantic_map.max_range_m", [](M& m) -> float& { return m.max_range_m; }, 0.1, 100,
        "points farther from the camera are not fused (rays are cut here)"));
    t.add(numberSetting<M, float>(
        "semantic_map.carve_margin_m", [](M& m) -> float& { return m.carve_margin_m; }, 0, 10,
        "free-space rays stop this short of the measured point"));
    t.add(numberSetting<M, float>(
        "semantic_map.hit_logodds", [](M& m) -> float& { return m.hit_logodds; }, 0.01, 125,
        "occupancy log-odds a frame's hit adds to a voxel"));
    t.add(numberSetting<M, float>(
        "semantic_map.miss_logodds", [](M& m) -> float& { return m.miss_logodds; }, 0.01, 125,
        "occupancy log-odds a ray through a voxel takes away (0 or below: removed)"));
    t.add(numberSetting<M, float>(
        "semantic_map.max_logodds", [](M& m) -> float& { return m.max_logodds; }, 0.01, 125,
        "occupancy log-odds cap (how many misses a long-seen voxel survives)"));
    t.add(numberSetting<M, float>(
        "semantic_map.seen_through_logodds",
        [](M& m) -> float& { return m.seen_through_logodds; }, 0, 125,
        "log-odds a table-top voxel loses in a frame whose depth lies behind it (0: off)"));
    t.add(integerSetting<M, int>(
        "semantic_map.max_voxels", [](M& m) -> int& { return m.max_voxels; }, 1000, 100000000,
        "memory bound: oldest voxels dropped above it (about 64 bytes each)"));
    t.add(integerSetting<M, int>(
        "semantic_map.min_table_voxels", [](M& m) -> int& { return m.min_table_voxels; }, 1,
        10000000, "table voxels a table from the map needs"));
    t.add(integerSetting<M, int>(
        "semantic_map.min_voxel_frames", [](M& m) -> int& { return m.min_voxel_frames; }, 1,
        65535, "frames a voxel must be seen in to count for tables"));
    t.add(numberSetting<M, float>(
        "semantic_map.table_match_gap_m", [](M& m) -> float& { return m.table_match_gap_m; }, 0,
        5, "a map table this close to an earlier one keeps its id"));
    t.add(integerSetting<M, int>(
        "semantic_map.support_frames", [](M& m) -> int& { return m.support_frames; }, 1, 1000000,
        "newest frames whose table votes are kept to count a table's support"));
    t.add(integerSetting<M, int>(
        "semantic_map.support_min_voxels", [](M& m) -> int& { return m.support_min_voxels; }, 1,
        1000000, "table-voted voxels by which a frame supports a table"));
    t.add(numberSetting<M, float>(
        "semantic_map.viewpoint_cell_m", [](M& m) -> float& { return m.viewpoint_cell_m; }, 0.01,
        100, "viewpoints: camera positions in cells of this size ..."));
    t.add(numberSetting<M, float>(
        "semantic_map.viewpoint_angle_deg", [](M& m) -> float& { return m.viewpoint_angle_deg; },
        1, 360, "... and headings in sectors of this angle"));
    return t;
  }();
  return table;
}

Eigen::Isometry3d cameraInMap(const Pose2D& base_in_map, const Eigen::Isometry3f& camera_to_base) {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.linear() = Eigen::AngleAxisd(base_in_map.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  base.translation() = Eigen::Vector3d(base_in_map.x, base_in_map.y, 0.0);
  return base * camera_to_base.cast<double>();
}

// ---- the map ---------------------------------------------------------------------------------

SemanticMap::SemanticMap(SemanticMapConfig map_config, TableConfig table_config)
    : map_config_(map_config), table_config_(table_config) {
  validateSemanticMapConfig(map_config_);
  validateTableConfig(table_config_);
}

void SemanticMap::clear() {
  voxels_.clear();
  support_.clear();
  previous_tables_.clear();  // ids are not reused: a client may still hold old ones
  frame_number_ = 0;
  last_utime_ = 0;
}

std::uint64_t SemanticMap::keyOf(const Eigen::Vector3d& p) const {
  // Voxels are centred on multiples of the voxel size: the floor (z = 0) lies in the
  // middle of one layer of voxels rather than on the border between two.
  const double inv = 1.0 / map_config_.voxel_size_m;
  return packIndices(static_cast<std::int64_t>(std::floor(p.x() * inv + 0.5)),
                     static_cast<std::int64_t>(std::floor(p.y() * inv + 0.5)),
                     static_cast<std::int64_t>(std::floor(p.z() * inv + 0.5)));
}

Eigen::Vector3d SemanticMap::centreOf(std::uint64_t key) const {
  return unpackIndices(key).cast<double>().matrix() *
         static_cast<double>(map_config_.voxel_size_m);
}

const SemanticMap::Voxel* SemanticMap::find(const Eigen::Vector3d& point_in_map) const {
  const auto it = voxels_.find(keyOf(point_in_map));
  return it == voxels_.end() ? nullptr : &it->second;
}

std::uint8_t SemanticMap::labelOf(const Voxel& voxel, float* confidence) {
  int best = -1;
  std::uint32_t best_votes = 0, total = 0;
  for (int l = 0; l < kNumLabels; ++l) {
    total += voxel.votes[l];
    if (voxel.votes[l] > best_votes) {
      best_votes = voxel.votes[l];
      best = l;
    }
  }
  if (confidence) *confidence = total ? static_cast<float>(best_votes) / static_cast<float>(total) : 0.0f;
  return best < 0 ? kVoidLabel : static_cast<std::uint8_t>(best);
}

std::uint64_t SemanticMap::viewpointOf(const Eigen::Isometry3d& camera_in_map) const {
  const Eigen::Vector3d forward = camera_in_map.linear().col(2);
  const double heading = std::atan2(forward.y(), forward.x()) + kPi;  // [0, 2 pi]
  const auto sectors = static_cast<std::int64_t>(std::ceil(360.0 / map_config_.viewpoint_angle_deg));
  const std::int64_t sector =
      std::min(sectors - 1, static_cast<std::int64_t>(heading * 180.0 / kPi /
                                                      map_config_.viewpoint_angle_deg));
  const double cell = map_config_.viewpoint_cell_m;
  return packIndices(static_cast<std::int64_t>(std::floor(camera_in_map.translation().x() / cell)),
                     static_cast<std::int64_t>(std::floor(camera_in_map.translation().y() / cell)),
                     sector);
}

SemanticMapUpdate SemanticMap::integrate(const OrganizedCloud& cloud, const LabelImage& labels,
                                         const Eigen::Isometry3d& camera_in_map,
                                         std::uint64_t utime) {
  const std::size_t pixels = static_cast<std::size_t>(std::max(cloud.width, 0)) *
                             static_cast<std::size_t>(std::max(cloud.height, 0));
  if (cloud.points.size() != pixels) {
    throw Error("semantic map: cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height) + " but holds " +
                std::to_string(cloud.points.size()) + " points");
  }
  if (labels.width != cloud.width || labels.height != cloud.height ||
      labels.labels.size() != pixels || labels.confidence.size() != pixels) {
    throw Error("semantic map: label image is " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " (" + std::to_string(labels.labels.size()) +
                " labels, " + std::to_string(labels.confidence.size()) +
                " confidences), cloud is " + std::to_string(cloud.width) + "x" +
                std::to_string(cloud.height));
  }
  if (!camera_in_map.matrix().allFinite() ||
      camera_in_map.translation().norm() > kMaxPoseDistanceM) {
    throw Error("semantic map: camera pose is not finite or farther than 10 km from the origin");
  }
  if (frame_number_ == std::numeric_limits<std::uint32_t>::max()) {
    throw Error("semantic map: frame counter exhausted; clear the map");
  }
  ++frame_number_;
  last_utime_ = std::max(last_utime_, utime);
  SemanticMapUpdate update;

  // The frame's hits, grouped by voxel.
  std::vector<Hit> hits;
  const int stride = map_config_.pixel_stride;
  const float max_range2 = map_config_.max_range_m * map_config_.max_range_m;
  hits.reserve(pixels / static_cast<std::size_t>(stride * stride) + 1);
  for (int y = 0; y < cloud.height; y += stride) {
    for (int x = 0; x < cloud.width; x += stride) {
      const std::size_t i = static_cast<std::size_t>(y) * cloud.width + x;
      const Eigen::Vector3f& p = cloud.points[i];
      if (!p.allFinite()) continue;
      const float range2 = p.squaredNorm();
      if (range2 > max_range2 || range2 <= 0.0f) continue;
      const float c = labels.confidence[i];
      hits.push_back({keyOf(camera_in_map * p.cast<double>()), labels.labels[i],
                      std::isfinite(c) ? std::clamp(c, 0.0f, 1.0f) : 0.0f});
    }
  }
  std::sort(hits.begin(), hits.end(),
            [](const Hit& a, const Hit& b) { return a.key < b.key; });

  const auto hit_step = static_cast<int>(std::lround(map_config_.hit_logodds * kLogOddsScale));
  const auto max_occupancy = static_cast<int>(std::lround(map_config_.max_logodds * kLogOddsScale));
  const double voxel = map_config_.voxel_size_m;
  SupportRecord record;
  record.viewpoint = viewpointOf(camera_in_map);
  for (std::size_t begin = 0; begin < hits.size();) {
    std::size_t end = begin;
    std::array<float, kNumLabels> sums{};
    while (end < hits.size() && hits[end].key == hits[begin].key) {
      if (hits[end].label < kNumLabels) sums[hits[end].label] += hits[end].confidence;
      ++end;
    }
    const auto n = static_cast<float>(end - begin);
    auto [it, created] = voxels_.try_emplace(hits[begin].key);
    Voxel& v = it->second;
    update.created += created ? 1 : 0;
    ++update.hits;
    v.occupancy = static_cast<std::int16_t>(std::min(max_occupancy, v.occupancy + hit_step));
    if (v.frames < 0xFFFF) ++v.frames;
    v.last_hit = frame_number_;
    int frame_label = -1;
    float frame_best = 0.0f;
    for (int l = 0; l < kNumLabels; ++l) {
      const int vote = static_cast<int>(std::lround(kVoteScale * sums[l] / n));
      if (vote > 0) addVote(v, l, vote);
      if (sums[l] > frame_best) {
        frame_best = sums[l];
        frame_label = l;
      }
    }
    if (frame_label == static_cast<int>(Label::Table)) {
      const double z = centreOf(hits[begin].key).z();
      if (z >= table_config_.min_table_height_m - voxel &&
          z <= table_config_.max_table_height_m + voxel) {
        const std::uint64_t column = columnOf(hits[begin].key);
        if (!record.table_cells.empty() && record.table_cells.back().first == column) {
          ++record.table_cells.back().second;
        } else {
          record.table_cells.emplace_back(column, 1);
        }
      }
    }
    begin = end;
  }
  // Sorted by key (x, y, z): equal columns are adjacent, and in column order.
  support_.push_back(std::move(record));
  while (static_cast<int>(support_.size()) > map_config_.support_frames) support_.pop_front();

  carve(cloud, camera_in_map, update);
  if (map_config_.seen_through_logodds > 0.0f) seeThrough(cloud, camera_in_map, update);
  update.dropped = enforceBound(camera_in_map.translation());
  return update;
}

void SemanticMap::carve(const OrganizedCloud& cloud, const Eigen::Isometry3d& camera_in_map,
                        SemanticMapUpdate& update) {
  // In voxel units shifted by half a voxel, so that cell indices are floor() of them
  // (keyOf).
  const double inv = 1.0 / map_config_.voxel_size_m;
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5);
  const Eigen::Vector3d origin = camera_in_map.translation() * inv + half;
  std::vector<std::uint64_t> crossed;
  const int stride = map_config_.carve_stride;
  for (int y = stride / 2; y < cloud.height; y += stride) {
    for (int x = stride / 2; x < cloud.width; x += stride) {
      const Eigen::Vector3f& p = cloud.points[static_cast<std::size_t>(y) * cloud.width + x];
      if (!p.allFinite()) continue;
      const double range = p.cast<double>().norm();
      if (range <= 0.0) continue;
      const double length = std::min<double>(range - map_config_.carve_margin_m,
                                              map_config_.max_range_m);
      if (length <= 0.0) continue;
      const Eigen::Vector3d dir_camera = p.cast<double>() / range;
      const Eigen::Vector3d target = (camera_in_map * (dir_camera * length)) * inv + half;
      // Voxel traversal (Amanatides & Woo) from origin to target.
      const Eigen::Vector3d d = target - origin;
      Eigen::Array3i cell = origin.array().floor().cast<int>();
      const Eigen::Array3i last = target.array().floor().cast<int>();
      Eigen::Array3i step;
      Eigen::Array3d t_max, t_delta;
      for (int a = 0; a < 3; ++a) {
        if (d[a] > 0) {
          step[a] = 1;
          t_max[a] = (cell[a] + 1 - origin[a]) / d[a];
          t_delta[a] = 1.0 / d[a];
        } else if (d[a] < 0) {
          step[a] = -1;
          t_max[a] = (cell[a] - origin[a]) / d[a];
          t_delta[a] = -1.0 / d[a];
        } else {
          step[a] = 0;
          t_max[a] = std::numeric_limits<double>::infinity();
          t_delta[a] = std::numeric_limits<double>::infinity();
        }
      }
      const int max_steps = (last - cell).abs().sum() + 1;
      for (int s = 0; s < max_steps; ++s) {
        const std::uint64_t key = packIndices(cell[0], cell[1], cell[2]);
        const auto it = voxels_.find(key);
        if (it != voxels_.end() && it->second.last_hit != frame_number_) crossed.push_back(key);
        if ((cell == last).all()) break;
        int a = 0;
        if (t_max[1] < t_max[a]) a = 1;
        if (t_max[2] < t_max[a]) a = 2;
        if (t_max[a] > 1.0) break;
        cell[a] += step[a];
        t_max[a] += t_delta[a];
      }
    }
  }
  std::sort(crossed.begin(), crossed.end());
  crossed.erase(std::unique(crossed.begin(), crossed.end()), crossed.end());
  const auto miss_step = static_cast<int>(std::lround(map_config_.miss_logodds * kLogOddsScale));
  for (std::uint64_t key : crossed) {
    const auto it = voxels_.find(key);
    ++update.carved;
    const int occupancy = it->second.occupancy - miss_step;
    if (occupancy <= 0) {
      voxels_.erase(it);
      ++update.removed;
    } else {
      it->second.occupancy = static_cast<std::int16_t>(occupancy);
    }
  }
  carved_total_ += static_cast<std::uint64_t>(update.removed);
}

namespace {

// The pinhole u = fx x/z + cx, v = fy y/z + cy of an organized cloud, fitted by least squares
// to every `stride`-th pixel's point. Fails (returns false) for clouds that are no pinhole
// image (too few points, RMS residual above half a pixel).
struct Pinhole {
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

bool fitPinhole(const OrganizedCloud& cloud, int stride, Pinhole& out) {
  struct Line {
    double n = 0, sa = 0, sb = 0, saa = 0, sab = 0;
    void add(double a, double b) {
      n += 1;
      sa += a;
      sb += b;
      saa += a * a;
      sab += a * b;
    }
    bool solve(double& slope, double& offset) const {
      const double det = n * saa - sa * sa;
      if (n < 8 || !(std::abs(det) > 1e-12 * n * n)) return false;
      slope = (n * sab - sa * sb) / det;
      offset = (sb - slope * sa) / n;
      return std::isfinite(slope) && std::isfinite(offset) && slope > 0;
    }
  } horizontal, vertical;
  auto each = [&](auto&& visit) {
    for (int y = stride / 2; y < cloud.height; y += stride) {
      for (int x = stride / 2; x < cloud.width; x += stride) {
        const Eigen::Vector3f& p = cloud.points[static_cast<std::size_t>(y) * cloud.width + x];
        if (p.allFinite() && p.z() > 0.0f) visit(x, y, p);
      }
    }
  };
  each([&](int x, int y, const Eigen::Vector3f& p) {
    horizontal.add(p.x() / p.z(), x);
    vertical.add(p.y() / p.z(), y);
  });
  if (!horizontal.solve(out.fx, out.cx) || !vertical.solve(out.fy, out.cy)) return false;
  double residual2 = 0.0;
  each([&](int x, int y, const Eigen::Vector3f& p) {
    const double du = out.fx * p.x() / p.z() + out.cx - x;
    const double dv = out.fy * p.y() / p.z() + out.cy - y;
    residual2 += du * du + dv * dv;
  });
  return residual2 / horizontal.n < 0.25;
}

}  // namespace

bool SemanticMap::tableVoxel(const Voxel& v) const {
  // As tables() decides: the table votes count tables.table_weight times.
  const std::uint8_t label = labelOf(v);
  const int table = static_cast<int>(Label::Table);
  return label == table ||
         (label != kVoidLabel && v.votes[table] * table_config_.table_weight > v.votes[label]);
}

void SemanticMap::seeThrough(const OrganizedCloud& cloud, const Eigen::Isometry3d& camera_in_map,
                             SemanticMapUpdate& update) {
  Pinhole pinhole;
  if (!fitPinhole(cloud, map_config_.carve_stride, pinhole)) return;
  const double voxel = map_config_.voxel_size_m;
  const auto z_low = static_cast<int>(std::floor(table_config_.min_table_height_m / voxel + 0.5)) - 1;
  const auto z_high = static_cast<int>(std::floor(table_config_.max_table_height_m / voxel + 0.5)) + 1;
  const double margin = map_config_.carve_margin_m + voxel;
  const double max_range = map_config_.max_range_m;
  const Eigen::Isometry3d map_to_camera = camera_in_map.inverse();
  const auto step =
      static_cast<int>(std::lround(map_config_.seen_through_logodds * kLogOddsScale));
  int removed = 0;
  for (auto it = voxels_.begin(); it != voxels_.end();) {
    const Voxel& v = it->second;
    const int z_index = static_cast<int>(static_cast<std::int64_t>(it->first & kKeyMask) - kKeyOffset);
    bool seen_through = false;
    if (z_index >= z_low && z_index <= z_high && v.last_hit != frame_number_ &&
        tableVoxel(v)) {
      const Eigen::Vector3d p = map_to_camera * centreOf(it->first);
      if (p.z() > 0.1 && p.norm() < max_range) {
        const double column = std::floor(pinhole.fx * p.x() / p.z() + pinhole.cx + 0.5);
        const double row = std::floor(pinhole.fy * p.y() / p.z() + pinhole.cy + 0.5);
        if (column >= 0 && row >= 0 && column < cloud.width && row < cloud.height) {
          const auto u = static_cast<int>(column), w = static_cast<int>(row);
          // The nearest depth at it and where its eight neighbour voxels project (one voxel
          // away in the image): a table edge, a pose error of up to a voxel or a thin thing
          // in front keeps it.
          const int reach = static_cast<int>(
              std::clamp(std::floor(pinhole.fx * voxel / p.z() + 0.5), 1.0,
                         static_cast<double>(std::max(cloud.width, cloud.height))));
          float nearest = std::numeric_limits<float>::infinity();
          for (int dy = -reach; dy <= reach; dy += reach) {
            for (int dx = -reach; dx <= reach; dx += reach) {
              const int qx = u + dx, qy = w + dy;
              if (qx < 0 || qy < 0 || qx >= cloud.width || qy >= cloud.height) continue;
              const Eigen::Vector3f& q =
                  cloud.points[static_cast<std::size_t>(qy) * cloud.width + qx];
              if (q.allFinite()) nearest = std::min(nearest, q.z());
            }
          }
          seen_through = std::isfinite(nearest) && nearest > p.z() + margin;
        }
      }
    }
    if (!seen_through) {
      ++it;
      continue;
    }
    ++update.seen_through;
    const int occupancy = it->second.occupancy - step;
    if (occupancy <= 0) {
      it = voxels_.erase(it);
      ++removed;
    } else {
      it->second.occupancy = static_cast<std::int16_t>(occupancy);
      ++it;
    }
  }
  update.removed += removed;
  carved_total_ += static_cast<std::uint64_t>(removed);
}

int SemanticMap::enforceBound(const Eigen::Vector3d& camera) {
  const auto bound = static_cast<std::size_t>(map_config_.max_voxels);
  if (voxels_.size() <= bound) return 0;
  const std::size_t keep = bound - bound / 10;
  struct Age {
    std::uint32_t last_hit;
    double distance2;
    std::uint64_t key;
  };
  std::vector<Age> ages;
  ages.reserve(voxels_.size());
  for (const auto& [key, v] : voxels_) {
    ages.push_back({v.last_hit, (centreOf(key) - camera).squaredNorm(), key});
  }
  const std::size_t drop = ages.size() - keep;
  // First `drop`: oldest last hit; among equals the farthest (ties: by key, deterministic).
  std::nth_element(ages.begin(), ages.begin() + static_cast<std::ptrdiff_t>(drop - 1), ages.end(),
                   [](const Age& a, const Age& b) {
                     if (a.last_hit != b.last_hit) return a.last_hit < b.last_hit;
                     if (a.distance2 != b.distance2) return a.distance2 > b.distance2;
                     return a.key < b.key;
                   });
  for (std::size_t i = 0; i < drop; ++i) voxels_.erase(ages[i].key);
  dropped_total_ += drop;
  return static_cast<int>(drop);
}

SemanticMapStats SemanticMap::stats() const {
  SemanticMapStats s;
  s.voxels = voxels_.size();
  s.frames = frame_number_;
  s.voxels_dropped = dropped_total_;
  s.voxels_carved = carved_total_;
  s.memory_bytes = voxels_.size() * kBytesPerVoxel;
  for (const auto& r : support_) {
    s.memory_bytes += sizeof(SupportRecord) + r.table_cells.capacity() * 16;
  }
  return s;
}

// ---- tables ---------------------------------------------------------------------------------

std::vector<FusedTable> SemanticMap::tables(std::vector<std::string>* diagnostics) {
  // Every voxel with enough evidence as one point of an unorganized cloud (width n,
  // height 1), labelled with its most voted label.
  // The table stage works near its origin (it refuses points 100 m away, and floats lose
  // millimetres far out): the voxels go in relative to their mean position on the floor,
  // those more than kTableRadiusM from it are left out, and the tables are moved back.
  constexpr double kTableRadiusM = 90.0;
  OrganizedCloud cloud;
  LabelImage labels;
  std::vector<Eigen::Vector3d> centres;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& [key, v] : voxels_) {
    if (!occupied(v) || v.frames < map_config_.min_voxel_frames) continue;
    float confidence = 0.0f;
    std::uint8_t label = labelOf(v, &confidence);
    if (label == kVoidLabel) continue;
    // As per frame (tables.table_weight, weightTableProbability): the table votes count
    // table_weight times when the voxel's label is decided for the table stage.
    const int table = static_cast<int>(Label::Table);
    if (label != table && v.votes[table] * table_config_.table_weight > v.votes[label]) {
      std::uint32_t total = 0;
      for (std::uint16_t n : v.votes) total += n;
      label = static_cast<std::uint8_t>(table);
      confidence = static_cast<float>(v.votes[table]) / static_cast<float>(total);
    }
    centres.push_back(centreOf(key));
    mean += centres.back().head<2>();
    labels.labels.push_back(label);
    labels.confidence.push_back(confidence);
  }
  if (!centres.empty()) mean /= static_cast<double>(centres.size());
  // Whole voxels: the shift moves no centre off the grid.
  const double voxel_m = map_config_.voxel_size_m;
  const Eigen::Vector2d shift = (mean / voxel_m).array().round().matrix() * voxel_m;
  {
    LabelImage near;
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const Eigen::Vector2d xy = centres[i].head<2>() - shift;
      if (xy.norm() > kTableRadiusM) continue;
      cloud.points.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                                static_cast<float>(centres[i].z()));
      near.labels.push_back(labels.labels[i]);
      near.confidence.push_back(labels.confidence[i]);
    }
    labels = std::move(near);
  }
  // Deterministic order whatever the hash table's (ties in the clustering and geometry).
  {
    std::vector<std::size_t> order(cloud.points.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const auto& p = cloud.points[a];
      const auto& q = cloud.points[b];
      return std::tie(p.x(), p.y(), p.z()) < std::tie(q.x(), q.y(), q.z());
    });
    OrganizedCloud sorted;
    LabelImage sorted_labels;
    for (std::size_t i : order) {
      sorted.points.push_back(cloud.points[i]);
      sorted_labels.labels.push_back(labels.labels[i]);
      sorted_labels.confidence.push_back(labels.confidence[i]);
    }
    cloud = std::move(sorted);
    labels = std::move(sorted_labels);
  }
  const int n = static_cast<int>(cloud.points.size());
  cloud.width = labels.width = n;
  cloud.height = labels.height = n > 0 ? 1 : 0;
  if (n == 0) cloud.width = labels.width = 0;
  cloud.colors.assign(cloud.points.size(), Rgb8{});

  TableConfig config = table_config_;
  config.point_stride = 1;
  config.min_cluster_points = map_config_.min_table_voxels;
  config.max_cluster_points = std::max(config.min_cluster_points, n);
  // Neighbouring voxel centres are one voxel apart, diagonal ones up to sqrt(3) voxels.
  config.cluster_tolerance_m =
      std::max(config.cluster_tolerance_m, 1.75f * map_config_.voxel_size_m);
  std::vector<FusedTable> out;
  if (n == 0) {
    previous_tables_.clear();
    return out;
  }
  TableDetection detection = detectTables(cloud, labels, config, nullptr);
  if (diagnostics) *diagnostics = std::move(detection.diagnostics);

  std::vector<bool> used(previous_tables_.size(), false);
  std::vector<MappedId> now;
  for (TableCluster& detected : detection.tables) {
    FusedTable fused;
    fused.voxels = detected.point_count;
    detected.pixels.clear();
    TableCluster table = transformTable(detected, Pose2D{shift.x(), shift.y(), 0.0});
    // The earlier table it overlaps most, or failing that the nearest within the gap.
    int best = -1;
    float best_overlap = 0.0f, best_gap = map_config_.table_match_gap_m;
    for (std::size_t j = 0; j < previous_tables_.size(); ++j) {
      if (used[j]) continue;
      const auto& hull = previous_tables_[j].hull;
      const float overlap = polygonArea(intersectConvex(table.hull, hull));
      if (overlap > best_overlap) {
        best_overlap = overlap;
        best = static_cast<int>(j);
      } else if (best_overlap == 0.0f) {
        const float gap = convexGap(table.hull, hull);
        if (gap <= best_gap) {
          best_gap = gap;
          best = static_cast<int>(j);
        }
      }
    }
    if (best >= 0) {
      used[static_cast<std::size_t>(best)] = true;
      table.id = previous_tables_[static_cast<std::size_t>(best)].id;
    } else {
      table.id = next_table_id_++;
    }
    fused.table = std::move(table);
    countSupport(fused);
    now.push_back({fused.table.id, fused.table.hull});
    out.push_back(std::move(fused));
  }
  previous_tables_ = std::move(now);
  std::sort(out.begin(), out.end(),
            [](const FusedTable& a, const FusedTable& b) { return a.table.id < b.table.id; });
  return out;
}

void SemanticMap::countSupport(FusedTable& fused) const {
  const auto& hull = fused.table.hull;
  if (hull.size() < 3) return;
  const float voxel = map_config_.voxel_size_m;
  // The floor cells under the table's footprint (grown by one voxel), ascending.
  Eigen::Vector2f lo = hull.front(), hi = hull.front();
  for (const auto& p : hull) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::vector<std::uint64_t> cells;
  const auto x0 = static_cast<std::int64_t>(std::floor(lo.x() / voxel + 0.5f)) - 1;
  const auto x1 = static_cast<std::int64_t>(std::floor(hi.x() / voxel + 0.5f)) + 1;
  const auto y0 = static_cast<std::int64_t>(std::floor(lo.y() / voxel + 0.5f)) - 1;
  const auto y1 = static_cast<std::int64_t>(std::floor(hi.y() / voxel + 0.5f)) + 1;
  for (std::int64_t x = x0; x <= x1; ++x) {
    for (std::int64_t y = y0; y <= y1; ++y) {
      const Eigen::Vector2f centre(static_cast<float>(x) * voxel, static_cast<float>(y) * voxel);
      if (insideConvexOrNear(centre, hull, voxel)) cells.push_back(packIndices(x, y, 0));
    }
  }
  std::sort(cells.begin(), cells.end());
  std::set<std::uint64_t> viewpoints;
  for (const SupportRecord& record : support_) {
    std::uint32_t votes = 0;
    auto c = cells.begin();
    for (const auto& [column, count] : record.table_cells) {
      c = std::lower_bound(c, cells.end(), column);
      if (c == cells.end()) break;
      if (*c == column) votes += count;
    }
    if (votes >= static_cast<std::uint32_t>(map_config_.support_min_voxels)) {
      ++fused.frames;
      viewpoints.insert(record.viewpoint);
    }
  }
  fused.viewpoints = static_cast<int>(viewpoints.size());
}

// ---- fused labels into a frame ------------------------------------------------------------------

LabelImage SemanticMap::projectLabels(const OrganizedCloud& cloud, const LabelImage& labels,
                                      const Eigen::Isometry3d& camera_in_map,
                                      int* replaced) const {
  if (labels.width != cloud.width || labels.height != cloud.height ||
      labels.labels.size() != cloud.points.size() ||
      labels.confidence.size() != cloud.points.size()) {
    throw Error("semantic map: label image " + std::to_string(labels.width) + "x" +
                std::to_string(labels.height) + " does not match the cloud " +
                std::to_string(cloud.width) + "x" + std::to_string(cloud.height));
  }
  if (!camera_in_map.matrix().allFinite()) {
    throw Error("semantic map: camera pose is not finite");
  }
  LabelImage out = labels;
  int count = 0;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) continue;
    const Voxel* v = find(camera_in_map * p.cast<double>());
    if (!v || !occupied(*v)) continue;
    float confidence = 0.0f;
    const std::uint8_t label = labelOf(*v, &confidence);
    if (label == kVoidLabel) continue;
    out.labels[i] = label;
    out.confidence[i] = confidence;
    ++count;
  }
  if (replaced) *replaced = count;
  return out;
}

// ---- save and load ----------------------------------------------------------------------------

std::vector<std::uint8_t> SemanticMap::toBytes() const {
  Writer w;
  for (char c : kMagic) w.put(c);
  w.put(kFileVersion);
  w.put(map_config_.voxel_size_m);
  w.put(frame_number_);
  w.put(last_utime_);
  w.put(dropped_total_);
  w.put(carved_total_);
  w.put(static_cast<std::int32_t>(next_table_id_));
  // Voxels by key, so that one map always gives the same bytes.
  std::vector<std::uint64_t> keys;
  keys.reserve(voxels_.size());
  for (const auto& entry : voxels_) keys.push_back(entry.first);
  std::sort(keys.begin(), keys.end());
  w.put(static_cast<std::uint64_t>(keys.size()));
  for (std::uint64_t key : keys) {
    const Voxel& v = voxels_.at(key);
    w.put(key);
    for (std::uint16_t votes : v.votes) w.put(votes);
    w.put(v.occupancy);
    w.put(v.frames);
    w.put(v.last_hit);
  }
  w.put(static_cast<std::uint32_t>(previous_tables_.size()));
  for (const MappedId& t : previous_tables_) {
    w.put(static_cast<std::int32_t>(t.id));
    w.put(static_cast<std::uint32_t>(t.hull.size()));
    for (const auto& p : t.hull) {
      w.put(p.x());
      w.put(p.y());
    }
  }
  w.put(static_cast<std::uint32_t>(support_.size()));
  for (const SupportRecord& r : support_) {
    w.put(r.viewpoint);
    w.put(static_cast<std::uint32_t>(r.table_cells.size()));
    for (const auto& [cell, count] : r.table_cells) {
      w.put(cell);
      w.put(count);
    }
  }
  const auto crc = static_cast<std::uint32_t>(
      crc32(0L, w.bytes.data(), static_cast<uInt>(w.bytes.size())));
  w.put(crc);
  return std::move(w.bytes);
}

void SemanticMap::save(const std::string& path) const {
  const std::vector<std::uint8_t> bytes = toBytes();
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("semantic map " + path + ": cannot open " + temporary + " for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      std::remove(temporary.c_str());
      throw Error("semantic map " + path + ": writing " + temporary + " failed");
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw Error("semantic map " + path + ": cannot rename " + temporary + " into place");
  }
}

void SemanticMap::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("semantic map " + path + ": cannot open the file");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
  if (in.bad()) throw Error("semantic map " + path + ": read error");
  loadBytes(bytes, path);
}

void SemanticMap::loadBytes(const std::vector<std::uint8_t>& bytes, const std::string& name) {
  SemanticMap loaded(map_config_, table_config_);
  loaded.deserialise(bytes, name);
  *this = std::move(loaded);
}

void SemanticMap::deserialise(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  const std::size_t header = sizeof(kMagic) + sizeof(std::uint32_t);
  Reader magic_reader(bytes, bytes.size(), path);
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    magic_reader.fail("not a findmug semantic map (bad magic)");
  }
  if (bytes.size() < header) magic_reader.fail("truncated while reading the version");
  std::uint32_t version = 0;
  std::memcpy(&version, bytes.data() + sizeof(kMagic), sizeof(version));
  if (version != kFileVersion) {
    magic_reader.fail("file version " + std::to_string(version) + ", this build reads version " +
                      std::to_string(kFileVersion));
  }
  if (bytes.size() < header + sizeof(std::uint32_t)) magic_reader.fail("truncated (no checksum)");
  const std::size_t body = bytes.size() - sizeof(std::uint32_t);
  std::uint32_t stored_crc = 0;
  std::memcpy(&stored_crc, bytes.data() + body, sizeof(stored_crc));
  const auto crc = static_cast<std::uint32_t>(crc32(0L, bytes.data(), static_cast<uInt>(body)));
  if (crc != stored_crc) {
    magic_reader.fail("checksum mismatch (the file is truncated or corrupt)");
  }

  Reader r(bytes, body, path);
  for (std::size_t i = 0; i < sizeof(kMagic); ++i) r.get<char>("the magic");
  r.get<std::uint32_t>("the version");
  const auto voxel_size = r.get<float>("the voxel size");
  if (voxel_size != map_config_.voxel_size_m) {
    r.fail("made with semantic_map.voxel_size_m = " + fmt(voxel_size) + ", the setting is " +
           fmt(map_config_.voxel_size_m));
  }
  frame_number_ = r.get<std::uint32_t>("the frame count");
  last_utime_ = r.get<std::uint64_t>("the last time");
  dropped_total_ = r.get<std::uint64_t>("the dropped count");
  carved_total_ = r.get<std::uint64_t>("the carved count");
  next_table_id_ = r.get<std::int32_t>("the next table id");
  if (next_table_id_ < 1) r.fail("next table id " + std::to_string(next_table_id_) + " below 1");

  const auto max_occupancy =
      static_cast<int>(std::lround(map_config_.max_logodds * kLogOddsScale));
  const std::uint64_t n_voxels = r.count(r.get<std::uint64_t>("the voxel count"), 32, "voxels");
  if (n_voxels > static_cast<std::uint64_t>(map_config_.max_voxels)) {
    r.fail(std::to_string(n_voxels) + " voxels, above semantic_map.max_voxels (" +
           std::to_string(map_config_.max_voxels) + ")");
  }
  voxels_.reserve(n_voxels);
  std::uint64_t previous_key = 0;
  for (std::uint64_t i = 0; i < n_voxels; ++i) {
    const auto key = r.get<std::uint64_t>("a voxel key");
    if (i > 0 && key <= previous_key) r.fail("voxel " + std::to_string(i) + ": keys not ascending");
    previous_key = key;
    Voxel v;
    for (auto& votes : v.votes) votes = r.get<std::uint16_t>("a voxel's votes");
    v.occupancy = r.get<std::int16_t>("a voxel's occupancy");
    v.frames = r.get<std::uint16_t>("a voxel's frame count");
    v.last_hit = r.get<std::uint32_t>("a voxel's last hit");
    if (unpackIndices(key).cast<double>().abs().maxCoeff() * voxel_size >
        kMaxPoseDistanceM + 100.0) {
      r.fail("voxel " + std::to_string(i) + ": more than 10 km from the map's origin");
    }
    if (v.occupancy <= 0 || v.occupancy > max_occupancy) {
      r.fail("voxel " + std::to_string(i) + ": occupancy " + std::to_string(v.occupancy) +
             " outside (0, " + std::to_string(max_occupancy) + "]");
    }
    if (v.last_hit > frame_number_ || v.frames == 0) {
      r.fail("voxel " + std::to_string(i) + ": frame numbers inconsistent with the map's " +
             std::to_string(frame_number_) + " frames");
    }
    voxels_.emplace(key, v);
  }

  const std::uint32_t n_tables = static_cast<std::uint32_t>(
      r.count(r.get<std::uint32_t>("the table count"), 8, "tables"));
  for (std::uint32_t i = 0; i < n_tables; ++i) {
    MappedId t;
    t.id = r.get<std::int32_t>("a table id");
    if (t.id < 1 || t.id >= next_table_id_) {
      r.fail("table id " + std::to_string(t.id) + " outside [1, " +
             std::to_string(next_table_id_) + ")");
    }
    const auto n_hull = r.count(r.get<std::uint32_t>("a hull size"), 8, "hull points");
    for (std::uint64_t k = 0; k < n_hull; ++k) {
      const float x = r.get<float>("a hull point");
      const float y = r.get<float>("a hull point");
      if (!std::isfinite(x) || !std::isfinite(y)) r.fail("table " + std::to_string(t.id) +
                                                          ": hull point not finite");
      t.hull.emplace_back(x, y);
    }
    previous_tables_.push_back(std::move(t));
  }

  const auto n_records = r.count(r.get<std::uint32_t>("the support count"), 12, "support records");
  for (std::uint64_t i = 0; i < n_records; ++i) {
    SupportRecord record;
    record.viewpoint = r.get<std::uint64_t>("a viewpoint");
    const auto n_cells = r.count(r.get<std::uint32_t>("a cell count"), 12, "table cells");
    record.table_cells.reserve(n_cells);
    for (std::uint64_t k = 0; k < n_cells; ++k) {
      const auto cell = r.get<std::uint64_t>("a table cell");
      const auto count = r.get<std::uint32_t>("a table cell's count");
      if (!record.table_cells.empty() && cell <= record.table_cells.back().first) {
        r.fail("support record " + std::to_string(i) + ": cells not ascending");
      }
      record.table_cells.emplace_back(cell, count);
    }
    support_.push_back(std::move(record));
  }
  while (static_cast<int>(support_.size()) > map_config_.support_frames) support_.pop_front();
  if (!r.atEnd()) r.fail("unexpected bytes after the support records");
}

}  // namespace findmug
