#include "findmug/settings/config.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/settings/settings.hpp"

namespace findmug {

const char* classSchemeName(ClassScheme scheme) {
  switch (scheme) {
    case ClassScheme::Nyu13:
      return "nyu13";
    case ClassScheme::Nyu40:
      return "nyu40";
    case ClassScheme::Labels:
      break;
  }
  return "labels";
}

namespace {

// One named setting of the segmenter (the shared mechanism, settings.hpp).
using CoreSetting = Setting<SegmenterConfig>;

std::string formatDouble(double v) { return formatSettingNumber(v); }

// Builders for the kinds of settings, with inclusive ranges (settings.hpp), for
// the segmenter's table (T defaults to SegmenterConfig) and the offline one.
template <typename T = SegmenterConfig>
Setting<T> floatSetting(std::string key, std::type_identity_t<std::function<float&(T&)>> field,
                        double lo, double hi) {
  Setting<T> s = numberSetting<T, float>(std::move(key), field, lo, hi);
  // Printed as the float widened to double with 9 digits ("0.00999999978"):
  // models store the feature settings in this text (extractionSettings) and
  // are compared with it, so it must not change.
  s.get = [field](const T& c) { return formatDouble(field(const_cast<T&>(c))); };
  return s;
}

template <typename T = SegmenterConfig>
Setting<T> intSetting(std::string key, std::type_identity_t<std::function<int&(T&)>> field,
                      long long lo, long long hi) {
  return integerSetting<T, int>(std::move(key), std::move(field), lo, hi);
}

CoreSetting doubleSetting(std::string key, std::function<double&(SegmenterConfig&)> field,
                          double lo, double hi) {
  return numberSetting<SegmenterConfig, double>(std::move(key), std::move(field), lo, hi);
}

template <typename T = SegmenterConfig>
Setting<T> boolSetting(std::string key, std::type_identity_t<std::function<bool&(T&)>> field) {
  return findmug::boolSetting<T>(std::move(key), std::move(field));
}

template <typename Enum, typename T = SegmenterConfig>
Setting<T> enumSetting(std::string key, std::type_identity_t<std::function<Enum&(T&)>> field,
                       std::vector<std::pair<std::string, Enum>> names) {
  return findmug::enumSetting<T, Enum>(std::move(key), std::move(field), std::move(names));
}

template <typename T = SegmenterConfig>
Setting<T> seedSetting(std::string key,
                       std::type_identity_t<std::function<std::uint64_t&(T&)>> field) {
  return integerSetting<T, std::uint64_t>(std::move(key), std::move(field), 0,
                                          std::numeric_limits<long long>::max());
}

// `setting` with its doc line (the listing of --help style tools).
template <typename T>
Setting<T> documented(Setting<T> setting, std::string doc) {
  setting.doc = std::move(doc);
  return setting;
}

// features.objects_columns' words, from the column sets' table.
std::vector<std::pair<std::string, ObjectColumns>> objectColumnsWords() {
  std::vector<std::pair<std::string, ObjectColumns>> words;
  for (const ObjectColumnSet& set : kObjectColumnSets) words.emplace_back(set.name, set.columns);
  return words;
}

CoreSetting baggingFractionSetting() {
  CoreSetting s;
  s.key = "forest.bagging_fraction";
  s.set = [](SegmenterConfig& c, const std::string& value) {
    const auto x = parseNumber(value);
    if (!x || *x <= 0 || *x > 1) {
      throwBadSettingValue("forest.bagging_fraction", value, "a number in (0, 1]");
    }
    c.forest.bagging_fraction = *x;
  };
  s.get = [](const SegmenterConfig& c) { return formatDouble(c.forest.bagging_fraction); };
  return s;
}

namespace {

// The point cloud and its normals.
std::vector<CoreSetting> cloudSettings() {
  using C = SegmenterConfig;
  return {
      floatSetting(
          "cloud.max_depth_m", [](C& c) -> float& { return c.max_depth_m; }, 0.5, 20),
      intSetting(
          "cloud.fill_depth_max_run_px", [](C& c) -> int& { return c.depth_holes.max_run_px; }, 0,
          10000),
      floatSetting(
          "cloud.fill_depth_smooth_tolerance",
          [](C& c) -> float& { return c.depth_holes.smooth_tolerance; }, 0, 1),
      intSetting(
          "normals.window_radius_px", [](C& c) -> int& { return c.normals.window_radius_px; }, 1,
          32),
      intSetting(
          "normals.smoothing_radius_px", [](C& c) -> int& { return c.normals.smoothing_radius_px; },
          0, 32),
      floatSetting(
          "normals.max_depth_jump_m", [](C& c) -> float& { return c.normals.max_depth_jump_m; },
          0.001, 1),
  };
}

// The ground plane.
std::vector<CoreSetting> groundSettings() {
  using C = SegmenterConfig;
  return {
      enumSetting<GroundSource>("ground.source",
                                [](C& c) -> GroundSource& { return c.ground.source; },
                                {{"auto", GroundSource::Auto},
                                 {"extrinsics", GroundSource::Extrinsics},
                                 {"floor_labels", GroundSource::FloorLabels},
                                 {"estimated", GroundSource::Estimated},
                                 {"gravity", GroundSource::Gravity}}),
      floatSetting(
          "ground.ransac_inlier_m", [](C& c) -> float& { return c.ground.ransac_inlier_m; }, 0.001,
          0.5),
      intSetting(
          "ground.ransac_iterations", [](C& c) -> int& { return c.ground.ransac_iterations; }, 1,
          100000),
      intSetting(
          "ground.min_floor_points", [](C& c) -> int& { return c.ground.min_floor_points; }, 3,
          10000000),
      floatSetting(
          "ground.min_inlier_fraction", [](C& c) -> float& { return c.ground.min_inlier_fraction; },
          0.01, 1),
      floatSetting(
          "ground.normal_agreement_deg",
          [](C& c) -> float& { return c.ground.normal_agreement_deg; }, 1, 90),
      floatSetting(
          "ground.min_camera_height_m", [](C& c) -> float& { return c.ground.min_camera_height_m; },
          0, 5),
      floatSetting(
          "ground.floor_percentile", [](C& c) -> float& { return c.ground.floor_percentile; }, 0,
          50),
      floatSetting(
          "ground.percentile_margin_m", [](C& c) -> float& { return c.ground.percentile_margin_m; },
          0, 5),
      floatSetting(
          "ground.prior_camera_height_m",
          [](C& c) -> float& { return c.ground.prior_camera_height_m; }, 0.05, 5),
      floatSetting(
          "ground.gravity_refine_deg", [](C& c) -> float& { return c.ground.gravity_refine_deg; },
          0, 89),
      floatSetting(
          "ground.max_tilt_deg", [](C& c) -> float& { return c.ground.max_tilt_deg; }, 1, 89),
      intSetting(
          "ground.reestimate_every_frames",
          [](C& c) -> int& { return c.ground.reestimate_every_frames; }, 1, 100000),
      floatSetting(
          "ground.reuse_min_support_fraction",
          [](C& c) -> float& { return c.ground.reuse_min_support_fraction; }, 0.01, 1),
  };
}

// The oversegmentation into patches.
std::vector<CoreSetting> oversegmentationSettings() {
  using C = SegmenterConfig;
  return {
      enumSetting<OversegmenterKind>(
          "oversegmentation.method",
          [](C& c) -> OversegmenterKind& { return c.oversegmentation.kind; },
          {{"pcl", OversegmenterKind::PclSupervoxels},
           {"organized", OversegmenterKind::Organized}}),
      floatSetting(
          "oversegmentation.voxel_resolution_m",
          [](C& c) -> float& { return c.oversegmentation.voxel_resolution_m; }, 0.001, 1),
      floatSetting(
          "oversegmentation.seed_resolution_m",
          [](C& c) -> float& { return c.oversegmentation.seed_resolution_m; }, 0.005, 5),
      floatSetting(
          "oversegmentation.color_importance",
          [](C& c) -> float& { return c.oversegmentation.color_importance; }, 0, 100),
      floatSetting(
          "oversegmentation.spatial_importance",
          [](C& c) -> float& { return c.oversegmentation.spatial_importance; }, 0, 100),
      floatSetting(
          "oversegmentation.normal_importance",
          [](C& c) -> float& { return c.oversegmentation.normal_importance; }, 0, 100),
      intSetting(
          "oversegmentation.min_segment_points",
          [](C& c) -> int& { return c.oversegmentation.min_segment_points; }, 1, 100000),
      intSetting(
          "oversegmentation.max_iterations",
          [](C& c) -> int& { return c.oversegmentation.max_iterations; }, 1, 100),
      floatSetting(
          "oversegmentation.organized_seed_density",
          [](C& c) -> float& { return c.oversegmentation.organized_seed_density; }, 0.01, 1000),
      intSetting(
          "oversegmentation.search_window_factor",
          [](C& c) -> int& { return c.oversegmentation.search_window_factor; }, 1, 10),
  };
}

// The feature rows: regions, scene, objects, auto-context.
std::vector<CoreSetting> featureSettings() {
  using C = SegmenterConfig;
  return {
      boolSetting("features.regions", [](C& c) -> bool& { return c.regions.enabled; }),
      floatSetting(
          "features.region_normal_angle_deg",
          [](C& c) -> float& { return c.regions.normal_angle_deg; }, 0, 180),
      floatSetting(
          "features.region_plane_distance_m",
          [](C& c) -> float& { return c.regions.plane_distance_m; }, 0, 1),
      boolSetting("features.scene", [](C& c) -> bool& { return c.scene.enabled; }),
      floatSetting(
          "features.scene_cell_m", [](C& c) -> float& { return c.scene.cell_m; }, 0.01, 1),
      intSetting(
          "features.scene_band_px", [](C& c) -> int& { return c.scene.band_px; }, 1, 640),
      boolSetting("features.objects", [](C& c) -> bool& { return c.objects.enabled; }),
      enumSetting<ObjectColumns>(
          "features.objects_columns", [](C& c) -> ObjectColumns& { return c.objects.columns; },
          objectColumnsWords()),
      floatSetting(
          "features.objects_concave_tolerance_deg",
          [](C& c) -> float& { return c.objects.concave_tolerance_deg; }, 0, 90),
      floatSetting(
          "features.objects_link_gap_m", [](C& c) -> float& { return c.objects.link_gap_m; }, 0, 1),
      floatSetting(
          "features.objects_step_m", [](C& c) -> float& { return c.objects.step_m; }, 0, 1),
      floatSetting(
          "features.objects_convex_margin", [](C& c) -> float& { return c.objects.convex_margin; },
          0, 2),
      floatSetting(
          "features.objects_floor_height_m",
          [](C& c) -> float& { return c.objects.floor_height_m; }, 0, 2),
      floatSetting(
          "features.objects_plane_min_area_m2",
          [](C& c) -> float& { return c.objects.plane_min_area_m2; }, 0, 100),
      floatSetting(
          "features.objects_orientation_tolerance_deg",
          [](C& c) -> float& { return c.objects.orientation_tolerance_deg; }, 0, 45),
      boolSetting("features.context", [](C& c) -> bool& { return c.context.enabled; }),
      floatSetting(
          "features.context_near_m", [](C& c) -> float& { return c.context.near_m; }, 0.01, 10),
      floatSetting(
          "features.context_far_m", [](C& c) -> float& { return c.context.far_m; }, 0.01, 10),
      floatSetting(
          "features.context_column_radius_m",
          [](C& c) -> float& { return c.context.column_radius_m; }, 0.01, 10),
      intSetting(
          "features.context_cross_fit_folds",
          [](C& c) -> int& { return c.context.cross_fit_folds; }, 0, 100),
  };
}

// The learner: the random forest, the boosted trees and what both use.
std::vector<CoreSetting> learnerSettings() {
  using C = SegmenterConfig;
  return {
      intSetting(
          "forest.num_trees", [](C& c) -> int& { return c.forest.num_trees; }, 1, 1000),
      intSetting(
          "forest.max_depth", [](C& c) -> int& { return c.forest.max_depth; }, 1, 40),
      intSetting(
          "forest.min_samples_leaf", [](C& c) -> int& { return c.forest.min_samples_leaf; }, 1,
          1000000),
      doubleSetting(
          "forest.shrinkage", [](C& c) -> double& { return c.forest.shrinkage; }, 0, 1e6),
      intSetting(
          "forest.candidate_features", [](C& c) -> int& { return c.forest.candidate_features; }, 1,
          1024),
      intSetting(
          "forest.candidate_thresholds", [](C& c) -> int& { return c.forest.candidate_thresholds; },
          1, 1000),
      enumSetting<LearnerKind>(
          "learner.kind", [](C& c) -> LearnerKind& { return c.learner.kind; },
          {{"forest", LearnerKind::Forest}, {"xgboost", LearnerKind::XGBoost}}),
      enumSetting<ClassScheme>("learner.classes",
                               [](C& c) -> ClassScheme& { return c.learner.classes; },
                               {{"labels", ClassScheme::Labels},
                                {"nyu13", ClassScheme::Nyu13},
                                {"nyu40", ClassScheme::Nyu40}}),
      enumSetting<ClassWeight>(
          "learner.class_weight", [](C& c) -> ClassWeight& { return c.learner.class_weight; },
          {{"labels", ClassWeight::Labels}, {"classes", ClassWeight::Classes}}),
      // Both learners train with these; ForestParams carries them to either.
      boolSetting("learner.class_weighting",
                  [](C& c) -> bool& { return c.forest.class_weighting; }),
      intSetting(
          "learner.num_threads", [](C& c) -> int& { return c.forest.num_threads; }, 0, 256),
      intSetting(
          "xgboost.rounds", [](C& c) -> int& { return c.xgboost.rounds; }, 1, 10000),
      intSetting(
          "xgboost.max_depth", [](C& c) -> int& { return c.xgboost.max_depth; }, 1, 30),
      doubleSetting(
          "xgboost.eta", [](C& c) -> double& { return c.xgboost.eta; }, 1e-6, 1),
      doubleSetting(
          "xgboost.subsample", [](C& c) -> double& { return c.xgboost.subsample; }, 1e-3, 1),
      doubleSetting(
          "xgboost.colsample", [](C& c) -> double& { return c.xgboost.colsample; }, 1e-3, 1),
      doubleSetting(
          "xgboost.min_child_weight", [](C& c) -> double& { return c.xgboost.min_child_weight; }, 0,
          1e6),
      doubleSetting(
          "xgboost.lambda", [](C& c) -> double& { return c.xgboost.lambda; }, 0, 1e6),
      intSetting(
          "xgboost.seed", [](C& c) -> int& { return c.xgboost.seed; }, 0, 2147483647),
  };
}

// The MRF and the label image.
std::vector<CoreSetting> mrfSettings() {
  using C = SegmenterConfig;
  return {
      boolSetting("mrf.enabled", [](C& c) -> bool& { return c.use_mrf; }),
      enumSetting<MrfPairwise>("mrf.pairwise", [](C& c) -> MrfPairwise& { return c.mrf.pairwise; },
                               {{"potts", MrfPairwise::Potts},
                                {"context", MrfPairwise::Context},
                                {"layout", MrfPairwise::Layout}}),
      findmug::textSetting<SegmenterConfig>(
          "mrf.layout_prior_path", [](C& c) -> std::string& { return c.mrf.layout_prior_path; },
          [](const std::string& v) {
            return v.empty() ? std::string("a file path") : std::string();
          }),
      floatSetting(
          "mrf.layout_weight", [](C& c) -> float& { return c.mrf.layout_weight; }, 0, 100),
      floatSetting(
          "mrf.layout_height_threshold",
          [](C& c) -> float& { return c.mrf.layout_height_threshold; }, 0, 10),
      enumSetting<LayoutDirection>(
          "mrf.layout_direction", [](C& c) -> LayoutDirection& { return c.mrf.layout_direction; },
          {{"height", LayoutDirection::Height}, {"image", LayoutDirection::Image}}),
      floatSetting(
          "mrf.layout_image_threshold_px",
          [](C& c) -> float& { return c.mrf.layout_image_threshold_px; }, 0, 10000),
      floatSetting(
          "mrf.object_consistency", [](C& c) -> float& { return c.mrf.object_consistency; }, 0, 1),
      floatSetting(
          "mrf.lambda", [](C& c) -> float& { return c.mrf.lambda; }, 0, 1000),
      floatSetting(
          "mrf.sigma", [](C& c) -> float& { return c.mrf.sigma; }, 1e-4, 100),
      intSetting(
          "mrf.max_iterations", [](C& c) -> int& { return c.mrf.max_iterations; }, 1, 10000),
      floatSetting(
          "mrf.damping", [](C& c) -> float& { return c.mrf.damping; }, 0, 0.99),
      floatSetting(
          "mrf.convergence_tol", [](C& c) -> float& { return c.mrf.convergence_tol; }, 0, 1),
      boolSetting("labels.fill_holes", [](C& c) -> bool& { return c.label_holes.enabled; }),
      intSetting(
          "labels.fill_max_run_px", [](C& c) -> int& { return c.label_holes.max_run_px; }, 1,
          10000),
  };
}

// Tables and their search positions.
std::vector<CoreSetting> tableSettings() {
  using C = SegmenterConfig;
  return {
      floatSetting(
          "tables.cluster_tolerance_m", [](C& c) -> float& { return c.tables.cluster_tolerance_m; },
          0.005, 1),
      intSetting(
          "tables.min_cluster_points", [](C& c) -> int& { return c.tables.min_cluster_points; }, 1,
          10000000),
      intSetting(
          "tables.max_cluster_points", [](C& c) -> int& { return c.tables.max_cluster_points; }, 1,
          10000000),
      intSetting(
          "tables.point_stride", [](C& c) -> int& { return c.tables.point_stride; }, 1, 8),
      floatSetting(
          "tables.safety_distance_m", [](C& c) -> float& { return c.tables.safety_distance_m; }, 0,
          5),
      floatSetting(
          "tables.arm_reach_m", [](C& c) -> float& { return c.tables.arm_reach_m; }, 0.05, 5),
      floatSetting(
          "tables.robot_radius_m", [](C& c) -> float& { return c.tables.robot_radius_m; }, 0, 3),
      floatSetting(
          "tables.min_table_height_m", [](C& c) -> float& { return c.tables.min_table_height_m; },
          0, 3),
      floatSetting(
          "tables.max_table_height_m", [](C& c) -> float& { return c.tables.max_table_height_m; },
          0, 3),
      floatSetting(
          "tables.top_band_m", [](C& c) -> float& { return c.tables.top_band_m; }, 0.005, 0.5),
      floatSetting(
          "tables.min_table_width_m", [](C& c) -> float& { return c.tables.min_table_width_m; }, 0,
          5),
      floatSetting(
          "tables.obstacle_min_height_m",
          [](C& c) -> float& { return c.tables.obstacle_min_height_m; }, 0, 2),
      floatSetting(
          "tables.robot_height_m", [](C& c) -> float& { return c.tables.robot_height_m; }, 0.1, 3),
      intSetting(
          "tables.obstacle_min_points", [](C& c) -> int& { return c.tables.obstacle_min_points; },
          1, 100000),
      floatSetting(
          "tables.floor_tolerance_m", [](C& c) -> float& { return c.tables.floor_tolerance_m; },
          0.005, 1),
      floatSetting(
          "tables.floor_cell_m", [](C& c) -> float& { return c.tables.floor_cell_m; }, 0.01, 1),
      floatSetting(
          "tables.min_floor_observed_fraction",
          [](C& c) -> float& { return c.tables.min_floor_observed_fraction; }, 0, 1),
      boolSetting("tables.region_vote", [](C& c) -> bool& { return c.tables.region_vote; }),
      floatSetting(
          "tables.table_weight", [](C& c) -> float& { return c.tables.table_weight; }, 0.01, 100),
      floatSetting(
          "tables.region_max_tilt_deg", [](C& c) -> float& { return c.tables.region_max_tilt_deg; },
          0, 90),
      floatSetting(
          "tables.region_min_area_m2", [](C& c) -> float& { return c.tables.region_min_area_m2; },
          0, 100),
      floatSetting(
          "tables.min_top_area_m2", [](C& c) -> float& { return c.tables.min_top_area_m2; }, 0,
          100),
      floatSetting(
          "tables.min_confidence", [](C& c) -> float& { return c.tables.min_confidence; }, 0, 1),
      floatSetting(
          "tables.min_horizontal_share",
          [](C& c) -> float& { return c.tables.min_horizontal_share; }, 0, 1),
      floatSetting(
          "tables.horizontal_tilt_deg", [](C& c) -> float& { return c.tables.horizontal_tilt_deg; },
          0, 90),
      floatSetting(
          "tables.soft_top_min_area_m2",
          [](C& c) -> float& { return c.tables.soft_top_min_area_m2; }, 0, 100),
      floatSetting(
          "tables.flat_tilt_deg", [](C& c) -> float& { return c.tables.flat_tilt_deg; }, 0, 90),
      floatSetting(
          "tables.min_flat_share", [](C& c) -> float& { return c.tables.min_flat_share; }, 0, 1),
      boolSetting("tables.relabel_soft_tops",
                  [](C& c) -> bool& { return c.tables.relabel_soft_tops; }),
  };
}

// The objects on the table tops (table_objects.hpp); ranges as
// validateTableObjectConfig's.
std::vector<CoreSetting> tableObjectSettings() {
  using C = SegmenterConfig;
  return {
      documented(boolSetting("table_objects.enabled",
                             [](C& c) -> bool& { return c.table_objects.enabled; }),
                 "look for object candidates standing on each table's top"),
      documented(floatSetting(
                     "table_objects.min_height_m",
                     [](C& c) -> float& { return c.table_objects.min_height_m; }, 0, 1),
                 "points at least this high above the top (m); lower is the top's depth noise"),
      documented(floatSetting(
                     "table_objects.max_height_m",
                     [](C& c) -> float& { return c.table_objects.max_height_m; }, 0.01, 3),
                 "points at most this high above the top (m); higher is a shelf, a lamp, a person"),
      documented(floatSetting(
                     "table_objects.outline_margin_m",
                     [](C& c) -> float& { return c.table_objects.outline_margin_m; }, 0, 0.5),
                 "the top's hull grown by this (m): an object at the edge hides the top under it"),
      documented(
          floatSetting(
              "table_objects.cluster_tolerance_m",
              [](C& c) -> float& { return c.table_objects.cluster_tolerance_m; }, 0.005, 0.5),
          "Euclidean clustering distance of the points above a top (m)"),
      documented(intSetting(
                     "table_objects.min_points",
                     [](C& c) -> int& { return c.table_objects.min_points; }, 1, 1000000),
                 "smaller clusters are dropped (a 5 cm mug 3 m away covers about 60 pixels)"),
      documented(floatSetting(
                     "table_objects.max_base_height_m",
                     [](C& c) -> float& { return c.table_objects.max_base_height_m; }, 0, 1),
                 "a candidate's lowest point at most this above the top (m): it stands there"),
      documented(floatSetting(
                     "table_objects.max_extent_m",
                     [](C& c) -> float& { return c.table_objects.max_extent_m; }, 0.01, 10),
                 "a candidate's longer footprint side at most this (m): not a chair back"),
      documented(floatSetting(
                     "table_objects.top_cell_m",
                     [](C& c) -> float& { return c.table_objects.top_cell_m; }, 0, 2),
                 "heights above the mean top in cells of this size (m); 0: the top height"),
      documented(intSetting(
                     "table_objects.point_stride",
                     [](C& c) -> int& { return c.table_objects.point_stride; }, 1, 8),
                 "cluster every Nth pixel of every Nth row, the others join a sampled neighbour"),
      documented(boolSetting("table_objects.relabel",
                             [](C& c) -> bool& { return c.table_objects.relabel; }),
                 "label a candidate's table-labelled pixels Object in the published labels"),
  };
}

// Last, so that each stays last in its section's listing: the seeds are
// 64-bit and the bagging fraction a double with an open lower end.
std::vector<CoreSetting> lastSettings() {
  using C = SegmenterConfig;
  return {
      seedSetting("forest.seed", [](C& c) -> std::uint64_t& { return c.forest.seed; }),
      baggingFractionSetting(),
      seedSetting("ground.seed", [](C& c) -> std::uint64_t& { return c.ground.seed; }),
  };
}

}  // namespace

const std::vector<CoreSetting>& settings() {
  static const std::vector<CoreSetting> all = [] {
    std::vector<CoreSetting> out;
    for (auto&& part : {cloudSettings(), groundSettings(), oversegmentationSettings(),
                        featureSettings(), learnerSettings(), mrfSettings(), tableSettings(),
                        tableObjectSettings(), lastSettings()}) {
      out.insert(out.end(), part.begin(), part.end());
    }
    return out;
  }();
  return all;
}

// The offline tools' settings (offline_settings.hpp).
const std::vector<Setting<OfflineConfig>>& offlineSettingList() {
  using O = OfflineConfig;
  static const std::vector<Setting<OfflineConfig>> all = {
      enumSetting<SampleWeighting, O>(
          "training.sample_weight",
          [](O& c) -> SampleWeighting& { return c.training.sample_weight; },
          {{"patches", SampleWeighting::Patches},
           {"pixels", SampleWeighting::Pixels},
           {"sqrt_pixels", SampleWeighting::SqrtPixels}}),
      enumSetting<SplitLabels, O>("training.split_labels",
                                  [](O& c) -> SplitLabels& { return c.training.split_labels; },
                                  {{"labels", SplitLabels::Labels},
                                   {"nyu40", SplitLabels::Nyu40},
                                   {"nyu13", SplitLabels::Nyu13}}),
      intSetting<O>(
          "training.extra_oversegmentations",
          [](O& c) -> int& { return c.training.extra_oversegmentations; }, 0, 8),
      floatSetting<O>(
          "training.extra_seed_scale", [](O& c) -> float& { return c.training.extra_seed_scale; },
          0.3, 0.99),
      intSetting<O>(
          "training.degraded_copies", [](O& c) -> int& { return c.training.degraded_copies; }, 0,
          8),
      intSetting<O>(
          "training.pseudo_rounds", [](O& c) -> int& { return c.training.pseudo_rounds; }, 0, 10),
      floatSetting<O>(
          "training.pseudo_min_confidence",
          [](O& c) -> float& { return c.training.pseudo_min_confidence; }, 0, 1),
      floatSetting<O>(
          "training.pseudo_weight", [](O& c) -> float& { return c.training.pseudo_weight; }, 0.001,
          1),
      floatSetting<O>(
          "training.pseudo_class_cap", [](O& c) -> float& { return c.training.pseudo_class_cap; },
          0, 1000),
      // 64-bit: parsed as an integer, never through a double.
      seedSetting<O>("training.degraded_seed",
                     [](O& c) -> std::uint64_t& { return c.training.degraded_seed; }),
      floatSetting<O>(
          "degrade.shadow_baseline_m", [](O& c) -> float& { return c.degrade.shadow_baseline_m; },
          -0.5, 0.5),
      floatSetting<O>(
          "degrade.shadow_focal_px", [](O& c) -> float& { return c.degrade.shadow_focal_px; }, 1,
          5000),
      floatSetting<O>(
          "degrade.edge_relative_jump", [](O& c) -> float& { return c.degrade.edge_relative_jump; },
          0.001, 10),
      intSetting<O>(
          "degrade.edge_band_px", [](O& c) -> int& { return c.degrade.edge_band_px; }, 0, 32),
      floatSetting<O>(
          "degrade.edge_hole_probability",
          [](O& c) -> float& { return c.degrade.edge_hole_probability; }, 0, 1),
      floatSetting<O>(
          "degrade.base_hole_probability",
          [](O& c) -> float& { return c.degrade.base_hole_probability; }, 0, 1),
      floatSetting<O>(
          "degrade.dark_level", [](O& c) -> float& { return c.degrade.dark_level; }, 0, 255),
      floatSetting<O>(
          "degrade.dark_hole_probability",
          [](O& c) -> float& { return c.degrade.dark_hole_probability; }, 0, 1),
      floatSetting<O>(
          "degrade.bright_level", [](O& c) -> float& { return c.degrade.bright_level; }, 0, 254),
      floatSetting<O>(
          "degrade.bright_hole_probability",
          [](O& c) -> float& { return c.degrade.bright_hole_probability; }, 0, 1),
      floatSetting<O>(
          "degrade.far_start_m", [](O& c) -> float& { return c.degrade.far_start_m; }, 0, 20),
      floatSetting<O>(
          "degrade.far_hole_per_m", [](O& c) -> float& { return c.degrade.far_hole_per_m; }, 0, 10),
      floatSetting<O>(
          "degrade.blob_size_px", [](O& c) -> float& { return c.degrade.blob_size_px; }, 0, 200),
      boolSetting<O>("degrade.quantise", [](O& c) -> bool& { return c.degrade.quantise; }),
      floatSetting<O>(
          "degrade.disparity_noise", [](O& c) -> float& { return c.degrade.disparity_noise; }, 0,
          20),
      floatSetting<O>(
          "degrade.max_input_hole_fraction",
          [](O& c) -> float& { return c.degrade.max_input_hole_fraction; }, 0, 1),
      intSetting<O>(
          "table_metrics.min_instance_points",
          [](O& c) -> int& { return c.table_metrics.min_instance_points; }, 1, 10000000),
      floatSetting<O>(
          "table_metrics.min_iou", [](O& c) -> float& { return c.table_metrics.min_iou; }, 0.01, 1),
      floatSetting<O>(
          "table_metrics.searchable_min_top_area_m2",
          [](O& c) -> float& { return c.table_metrics.searchable_min_top_area_m2; }, 0, 100),
      floatSetting<O>(
          "table_metrics.searchable_min_overlap",
          [](O& c) -> float& { return c.table_metrics.searchable_min_overlap; }, 0.01, 1),
      floatSetting<O>(
          "table_metrics.searchable_max_height_error_m",
          [](O& c) -> float& { return c.table_metrics.searchable_max_height_error_m; }, 0, 10),
  };
  return all;
}

// A table over every section its settings name, in the order they first appear.
template <typename T>
SettingsTable<T> tableOf(const std::vector<Setting<T>>& list) {
  std::vector<std::string> sections;
  for (const auto& s : list) {
    const std::string section = SettingsTable<T>::sectionOf(s.key);
    if (std::find(sections.begin(), sections.end(), section) == sections.end()) {
      sections.push_back(section);
    }
  }
  SettingsTable<T> t(std::move(sections));
  for (const auto& s : list) t.add(s);
  return t;
}

}  // namespace

const SettingsTable<SegmenterConfig>& segmenterSettings() {
  static const SettingsTable<SegmenterConfig> table = tableOf(settings());
  return table;
}

const SettingsTable<OfflineConfig>& offlineSettings() {
  static const SettingsTable<OfflineConfig> table = tableOf(offlineSettingList());
  return table;
}

void validateOfflineConfig(const OfflineConfig& offline, const SegmenterConfig& segmenter) {
  if (segmenter.learner.classes != ClassScheme::Labels &&
      offline.training.split_labels != SplitLabels::Labels) {
    throw Error(std::string("learner.classes = ") + classSchemeName(segmenter.learner.classes) +
                " cannot be combined with training.split_labels (the internal classes already "
                "choose the splits); set training.split_labels = labels");
  }
}

void validateSegmenterConfig(const SegmenterConfig& c) {
  if (c.oversegmentation.seed_resolution_m <= c.oversegmentation.voxel_resolution_m) {
    throw Error("oversegmentation.seed_resolution_m (" +
                formatDouble(c.oversegmentation.seed_resolution_m) +
                ") must be larger than oversegmentation.voxel_resolution_m (" +
                formatDouble(c.oversegmentation.voxel_resolution_m) + ")");
  }
  if (c.tables.min_table_height_m >= c.tables.max_table_height_m) {
    throw Error("tables.min_table_height_m must be below tables.max_table_height_m");
  }
  if (c.tables.arm_reach_m <= c.tables.safety_distance_m) {
    throw Error("tables.arm_reach_m (" + formatDouble(c.tables.arm_reach_m) +
                ") must exceed tables.safety_distance_m (" +
                formatDouble(c.tables.safety_distance_m) +
                "): from a search position the arm must reach past the table edge");
  }
  if (c.learner.kind == LearnerKind::XGBoost && c.context.enabled) {
    throw Error(
        "learner.kind = xgboost has no auto-context round; set "
        "features.context = false or learner.kind = forest");
  }
  if (c.tables.min_cluster_points > c.tables.max_cluster_points) {
    throw Error("tables.min_cluster_points must not exceed tables.max_cluster_points");
  }
  validateTableObjectConfig(c.table_objects);
}

void bindCoreSettings(SettingsSchema& schema, Config& config) {
  schema.bind(segmenterSettings(), config.segmenter, validateSegmenterConfig);
}

void bindOfflineSettings(SettingsSchema& schema, Config& config) {
  const SegmenterConfig& segmenter = config.segmenter;
  schema.bind(offlineSettings(), config.offline, [&segmenter](const OfflineConfig& offline) {
    validateOfflineConfig(offline, segmenter);
  });
}

Config parseConfig(const std::string& yaml_text, const std::string& origin) {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  schema.readYaml(yaml_text, origin);
  schema.validate(origin);
  return config;
}

Config loadConfig(const std::string& path) {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  schema.readFile(path);
  schema.validate(path);
  return config;
}

void applyOverride(Config& config, const std::string& key_equals_value) {
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  schema.applyOverride(key_equals_value);
  schema.validate("<flags>");
}

std::string dumpConfig(const Config& config) {
  Config copy = config;
  SettingsSchema schema;
  bindCoreSettings(schema, copy);
  bindOfflineSettings(schema, copy);
  return schema.dump();
}

RandomForest::Settings extractionSettings(const SegmenterConfig& config) {
  RandomForest::Settings out;
  for (const auto& s : settings()) {
    if (s.key == "features.context_cross_fit_folds") continue;  // training only
    // Which gaps get depth changes which pixels have points, not what a
    // feature means: a model serves filled and raw depth alike.
    if (s.key.rfind("cloud.fill_depth_", 0) == 0) continue;
    if (s.key.rfind("cloud.", 0) == 0 || s.key.rfind("normals.", 0) == 0 ||
        s.key.rfind("oversegmentation.", 0) == 0 || s.key.rfind("features.", 0) == 0) {
      out.emplace_back(s.key, s.get(config));
    }
  }
  return out;
}

}  // namespace findmug
