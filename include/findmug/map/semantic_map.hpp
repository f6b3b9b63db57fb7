// findmug/map/semantic_map.hpp — a 3-D semantic map fused from labelled frames seen from many poses.
//
// One frame's labels are noisy (BENCHMARKS.md 1g); a robot sees each table from many poses.
// SemanticMap keeps, per voxel of the map frame (z up, floor at z = 0: the robot base frame
// moved by the base's 2-D pose), how often each of the eight labels was seen there, weighted
// by the confidence the frame gave, and whether the voxel is still occupied:
//
//   * integrate(): one labelled frame (its camera-frame organized cloud, its label image with
//     confidences) with the camera's pose in the map (cameraInMap: robot pose ∘ camera mount).
//     Every `pixel_stride`-th pixel with a point within `max_range_m` is a hit. Each voxel
//     gets ONE vote per frame, however many pixels fall in it: for each label,
//     kVoteScale * (sum of its pixels' confidences) / (pixels in the voxel), so near voxels,
//     which hold many pixels, do not outvote far ones, and one bad frame is one vote.
//     Occupancy is log-odds: a hit adds `hit_logodds` (up to `max_logodds`).
//   * Free-space carving: rays from the camera to every `carve_stride`-th pixel's point
//     (stopping `carve_margin_m` short of it, or at `max_range_m`) pass through voxels
//     that are then seen to be empty: each mapped voxel on a ray (not hit by this frame)
//     loses `miss_logodds`, at most once per frame, and is removed when its occupancy
//     reaches 0. So a moved table or a passing person fades after a few views of the
//     space behind it. Only mapped voxels are touched: free space is never stored.
//   * Seen through (`seen_through_logodds`): carving rays are sparse (every 8th pixel), so a
//     table top seen a few times after it left keeps its saturated occupancy. So each
//     frame also projects every mapped table-top voxel (Table as tables() decides, at
//     table height, not hit by this frame) into the image (the pinhole fitted to the organized cloud's
//     pixels, since the cloud carries no intrinsics) and, where the nearest depth at it and
//     at its 8 neighbour voxels' pixels lies more than carve_margin_m + one voxel behind it, takes
//     `seen_through_logodds` from it (once per frame), removing it at 0. Its cost is one
//     pass over the voxels per frame (docs/measurements/semantic-map-seen-through.md).
//   * Bounded memory: at most `max_voxels` voxels. After a frame that leaves more, the
//     voxels seen longest ago (oldest last hit; among equals, farthest from the camera)
//     are dropped until 90 % of the bound is left. Budget: a voxel costs about
//     kBytesPerVoxel bytes (24 bytes of state, its 8-byte key and the hash table's node
//     and bucket); the default bound, 1 000 000 voxels, is ~64 MB. A 15 x 15 x 3 m
//     apartment at 5 cm has ~250 000 surface voxels (floor, ceiling, 120 m of walls,
//     furniture), a noisy surface twice that: within the default bound. The per-frame
//     support records (below) add at most `support_frames` small records.
//   * Tables from the map (tables()): the voxels whose most voted label is Table, the
//     table votes counting tables.table_weight times as per frame (1.5: the fused tops
//     grow to the true ones, seed 1 of docs/measurements/semantic-map.md), at table height, go
//     through the per-frame table stage (detectTables, the same
//     `tables.*` rules: clustering, geometry, search positions, reachability against the
//     map's floor and obstacle voxels), with each voxel centre as one point. Point counts
//     are voxels here (`min_table_voxels`), and the clustering tolerance is at least the
//     voxel diagonal, since voxel centres sample a surface at voxel spacing. Ids are stable:
//     a table keeps the id of the earlier table whose footprint it overlaps or comes
//     within `table_match_gap_m` of. Each table says how many of the last `support_frames`
//     integrated frames voted Table into its footprint (at least `support_min_voxels`
//     voxels) and from how many distinct viewpoints (camera cells of `viewpoint_cell_m`
//     and `viewpoint_angle_deg`).
//   * Fused labels back into a frame (projectLabels): each valid pixel whose point falls in
//     a mapped, occupied voxel with votes takes the voxel's label and confidence (its
//     share of the votes); other pixels keep the frame's own.
//   * save()/load(): a versioned binary file ending in a CRC-32 of everything before it;
//     a truncated, corrupt or foreign file, or one made with another voxel size, is refused
//     with a findmug::Error naming the file and the problem.
//
// Why a hashed voxel grid and not OctoMap (liboctomap-dev): the map's cost is per hit and
// per ray step, both one hash look-up here; OctoMap walks 16 tree levels for each and would
// need its own node type (with (de)serialisation) for the label votes anyway, while its
// strength, pruning uniform regions, does not apply: free space is never stored here, and
// occupied surface voxels with different votes do not prune. A flat grid also makes the
// bounded-memory rule (drop the oldest voxels) a linear pass and the file format ours.
//
// Pure core code: no LCM, no clock, no threads; the caller passes the time (utime).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <unordered_map>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/pose2d.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

struct SemanticMapConfig {
  float voxel_size_m = 0.05f;
  int pixel_stride = 2;      // every n-th pixel of every n-th row is a hit
  int carve_stride = 8;      // every n-th pixel of every n-th row casts a carving ray
  float max_range_m = 4.5f;  // points farther from the camera are not hits (Kinect noise)
  float carve_margin_m = 0.1f;  // carving stops this short of the measured point
  float hit_logodds = 0.85f;
  float miss_logodds = 0.4f;
  float max_logodds = 3.5f;
  // "Seen through": a mapped table-top voxel that projects into the frame where the depth
  // (nearest at it and one voxel around it) lies clearly behind it loses this much log-odds
  // in that frame, beside the sparse carving (0: off). The camera looked through where the
  // top was, so a moved table goes within a few views of its old place.
  float seen_through_logodds = 1.0f;
  int max_voxels = 1000000;
  // Tables from the map.
  int min_table_voxels = 40;         // 0.1 m^2 of top at 5 cm
  int min_voxel_frames = 2;          // a voxel seen in fewer frames is left out of tables()
  float table_match_gap_m = 0.15f;   // footprints this close keep one id
  int support_frames = 2000;         // newest frames whose table votes are kept for support
  int support_min_voxels = 5;        // a frame supports a table with this many Table votes in it
  float viewpoint_cell_m = 0.5f;     // viewpoints: camera position cells ...
  float viewpoint_angle_deg = 30.0f;  // ... and heading sectors
};

// Throws findmug::Error naming the setting (as `semantic_map.KEY`) when out of range.
void validateSemanticMapConfig(const SemanticMapConfig& config);
// The `semantic_map:` section of the config file, one key per field above.
const SettingsTable<SemanticMapConfig>& semanticMapSettings();

// The camera's pose in the map: the robot base's 2-D pose in the map composed with the
// camera mount (camera frame -> base frame, e.g. GroundPlane::camera_to_ground).
Eigen::Isometry3d cameraInMap(const Pose2D& base_in_map, const Eigen::Isometry3f& camera_to_base);

struct FusedTable {
  TableCluster table;  // map frame; table.id is the stable id (1, 2, ...; never reused)
  int voxels = 0;      // its table voxels
  int frames = 0;      // of the last support_frames integrated frames, those that voted Table in it
  int viewpoints = 0;  // distinct viewpoint cells among those frames
};

struct SemanticMapStats {
  std::size_t voxels = 0;
  std::uint64_t frames = 0;          // frames integrated
  std::uint64_t voxels_dropped = 0;  // by the memory bound, in all
  std::uint64_t voxels_carved = 0;   // removed by carving, in all
  std::size_t memory_bytes = 0;      // estimate: voxels * kBytesPerVoxel + support records
};

// What one integrate() did.
struct SemanticMapUpdate {
  int hits = 0;          // voxels that got this frame's vote
  int created = 0;       // of them new
  int carved = 0;        // voxels that lost occupancy along rays
  int seen_through = 0;  // table-top voxels the frame saw through (removed ones count in removed)
  int removed = 0;       // of them removed (occupancy reached 0)
  int dropped = 0;       // voxels dropped by the memory bound
};

class SemanticMap {
 public:
  // One frame's vote for a label is at most this many units (a voxel's counts are 16 bit;
  // when one would overflow, all of the voxel's counts are halved: old evidence weighs less).
  static constexpr int kVoteScale = 64;
  static constexpr std::size_t kBytesPerVoxel = 64;
  static constexpr std::uint32_t kFileVersion = 1;

  struct Voxel {
    std::array<std::uint16_t, kNumLabels> votes{};  // confidence-weighted, kVoteScale per frame
    std::int16_t occupancy = 0;  // log-odds * kLogOddsScale
    std::uint16_t frames = 0;    // frames that hit it (saturates)
    std::uint32_t last_hit = 0;  // frame number (1, 2, ...) of the last hit
  };
  static constexpr float kLogOddsScale = 256.0f;

  explicit SemanticMap(SemanticMapConfig map_config = {}, TableConfig table_config = {});

  // Fuses one labelled frame: `cloud_camera` in the camera frame (x right, y down, z
  // forward), `labels` on the same grid, `camera_in_map` its pose. Throws findmug::Error
  // when sizes disagree or the pose is not finite or beyond 10 km.
  SemanticMapUpdate integrate(const OrganizedCloud& cloud_camera, const LabelImage& labels,
                              const Eigen::Isometry3d& camera_in_map, std::uint64_t utime);

  // The tables of the map now (see the header comment), by id. Not const: it keeps the
  // ids for the next call. `diagnostics` (optional): why clusters were dropped.
  std::vector<FusedTable> tables(std::vector<std::string>* diagnostics = nullptr);

  // The map's labels in the frame (see the header comment). `replaced` (optional): pixels
  // that took the map's label.
  LabelImage projectLabels(const OrganizedCloud& cloud_camera, const LabelImage& labels,
                           const Eigen::Isometry3d& camera_in_map, int* replaced = nullptr) const;

  // The voxel holding `point_in_map`, or nullptr.
  const Voxel* find(const Eigen::Vector3d& point_in_map) const;
  // Its most voted label (kVoidLabel without votes) and that label's share of the votes.
  static std::uint8_t labelOf(const Voxel& voxel, float* confidence = nullptr);
  bool occupied(const Voxel& voxel) const { return voxel.occupancy > 0; }

  // Every voxel: its centre in the map and its state (order unspecified).
  template <class Visit>
  void forEachVoxel(Visit&& visit) const {
    for (const auto& [key, voxel] : voxels_) visit(centreOf(key), voxel);
  }

  SemanticMapStats stats() const;
  std::size_t size() const { return voxels_.size(); }
  void clear();
  const SemanticMapConfig& config() const { return map_config_; }

  // Writes the map to `path` (via a temporary file renamed into place). Throws
  // findmug::Error naming the file when it cannot be written.
  void save(const std::string& path) const;
  // Replaces this map with the one in `path`. Throws findmug::Error naming the file and the
  // problem (missing, truncated, bad magic, other version, checksum, another voxel size,
  // values out of range); the map is unchanged then.
  void load(const std::string& path);
  // The same from bytes in memory (`name` stands for the file in messages), and the bytes
  // save() writes.
  void loadBytes(const std::vector<std::uint8_t>& bytes, const std::string& name);
  std::vector<std::uint8_t> toBytes() const;

  // The voxel key of a point (exposed for tests): three 21-bit voxel indices.
  std::uint64_t keyOf(const Eigen::Vector3d& point_in_map) const;
  Eigen::Vector3d centreOf(std::uint64_t key) const;

 private:
  struct SupportRecord {
    std::uint64_t viewpoint = 0;
    // Floor cells (voxel columns, packed x/y indices) with how many voxels got a Table
    // vote there in this frame, ascending by cell.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> table_cells;
  };
  struct MappedId {
    int id = 0;
    std::vector<Eigen::Vector2f> hull;
  };

  void carve(const OrganizedCloud& cloud_camera, const Eigen::Isometry3d& camera_in_map,
             SemanticMapUpdate& update);
  void seeThrough(const OrganizedCloud& cloud_camera, const Eigen::Isometry3d& camera_in_map,
                  SemanticMapUpdate& update);
  bool tableVoxel(const Voxel& voxel) const;  // tables() would label it Table
  int enforceBound(const Eigen::Vector3d& camera);
  std::uint64_t viewpointOf(const Eigen::Isometry3d& camera_in_map) const;
  void countSupport(FusedTable& table) const;
  void deserialise(const std::vector<std::uint8_t>& bytes, const std::string& path);

  SemanticMapConfig map_config_;
  TableConfig table_config_;
  std::unordered_map<std::uint64_t, Voxel> voxels_;
  std::deque<SupportRecord> support_;
  std::vector<MappedId> previous_tables_;
  int next_table_id_ = 1;
  std::uint32_t frame_number_ = 0;
  std::uint64_t last_utime_ = 0;
  std::uint64_t dropped_total_ = 0;
  std::uint64_t carved_total_ = 0;
};

}  // namespace findmug
