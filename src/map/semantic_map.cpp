// semantic_map.cpp — label votes fused in a hashed voxel grid (see semantic_map.hpp): votes,
// free-space carving, the seen-through check and the bound on its size.
#include "findmug/map/semantic_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "findmug/common/error.hpp"
#include "semantic_map_internal.hpp"

namespace findmug {

using namespace semantic_map_detail;

namespace {

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

}  // namespace

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
  return unpackIndices(key).cast<double>().matrix() * static_cast<double>(map_config_.voxel_size_m);
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
  if (confidence)
    *confidence = total ? static_cast<float>(best_votes) / static_cast<float>(total) : 0.0f;
  return best < 0 ? kVoidLabel : static_cast<std::uint8_t>(best);
}

std::uint64_t SemanticMap::viewpointOf(const Eigen::Isometry3d& camera_in_map) const {
  const Eigen::Vector3d forward = camera_in_map.linear().col(2);
  const double heading = std::atan2(forward.y(), forward.x()) + kPi;  // [0, 2 pi]
  const auto sectors =
      static_cast<std::int64_t>(std::ceil(360.0 / map_config_.viewpoint_angle_deg));
  const std::int64_t sector =
      std::min(sectors - 1,
               static_cast<std::int64_t>(heading * 180.0 / kPi / map_config_.viewpoint_angle_deg));
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
                std::to_string(cloud.height) + " but holds " + std::to_string(cloud.points.size()) +
                " points");
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
  std::sort(hits.begin(), hits.end(), [](const Hit& a, const Hit& b) { return a.key < b.key; });

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
      const double length =
          std::min<double>(range - map_config_.carve_margin_m, map_config_.max_range_m);
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
  const auto z_low =
      static_cast<int>(std::floor(table_config_.min_table_height_m / voxel + 0.5)) - 1;
  const auto z_high =
      static_cast<int>(std::floor(table_config_.max_table_height_m / voxel + 0.5)) + 1;
  const double margin = map_config_.carve_margin_m + voxel;
  const double max_range = map_config_.max_range_m;
  const Eigen::Isometry3d map_to_camera = camera_in_map.inverse();
  const auto step = static_cast<int>(std::lround(map_config_.seen_through_logodds * kLogOddsScale));
  int removed = 0;
  for (auto it = voxels_.begin(); it != voxels_.end();) {
    const Voxel& v = it->second;
    const int z_index =
        static_cast<int>(static_cast<std::int64_t>(it->first & kKeyMask) - kKeyOffset);
    bool seen_through = false;
    if (z_index >= z_low && z_index <= z_high && v.last_hit != frame_number_ && tableVoxel(v)) {
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

}  // namespace findmug
