// segmenter_settings.cpp — the segmenter's settings table (segmenterSettings,
// findmug/settings/config.hpp): every key of SegmenterConfig, by section, each with its
// range, doc line and whether a model records it.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/settings/config.hpp"
#include "settings/setting_builders_internal.hpp"

namespace findmug {

// Inside settings_internal, so that its builders hide the mechanism's of the same name.
namespace settings_internal {
namespace {

// features.objects_columns' words, from the column sets' table.
std::vector<std::pair<std::string, ObjectColumns>> objectColumnsWords() {
  std::vector<std::pair<std::string, ObjectColumns>> words;
  for (const ObjectColumnSet& set : kObjectColumnSets) words.emplace_back(set.name, set.columns);
  return words;
}

CoreSetting baggingFractionSetting() {
  CoreSetting s;
  s.key = "forest.bagging_fraction";
  s.doc = "share of the training samples each tree is trained on";
  s.expected = "a number in (0, 1]";
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

// The point cloud and its normals.
std::vector<CoreSetting> cloudSettings() {
  using C = SegmenterConfig;
  return {
      recorded(documented(
          floatSetting(
              "cloud.max_depth_m", [](C& c) -> float& { return c.max_depth_m; }, 0.5, 20),
          "depth beyond this (m) is treated as missing")),
      documented(intSetting(
                     "cloud.fill_depth_max_run_px",
                     [](C& c) -> int& { return c.depth_holes.max_run_px; }, 0, 10000),
                 "depth gaps up to this long (px, along a column then a row) are filled before the "
                 "cloud is made; 0 = off"),
      documented(floatSetting(
                     "cloud.fill_depth_smooth_tolerance",
                     [](C& c) -> float& { return c.depth_holes.smooth_tolerance; }, 0, 1),
                 "a gap is interpolated when its ends lie within this share of the farther depth, "
                 "else takes the farther depth"),
      recorded(documented(intSetting(
                              "normals.window_radius_px",
                              [](C& c) -> int& { return c.normals.window_radius_px; }, 1, 32),
                          "half size (px) of the neighbourhood a normal is estimated from")),
      recorded(documented(intSetting(
                              "normals.smoothing_radius_px",
                              [](C& c) -> int& { return c.normals.smoothing_radius_px; }, 0, 32),
                          "box average radius (px) of the per-pixel normals; 0 = none")),
      recorded(documented(
          floatSetting(
              "normals.max_depth_jump_m", [](C& c) -> float& { return c.normals.max_depth_jump_m; },
              0.001, 1),
          "neighbours whose depth jumps more than this (x depth, m) are left out of a normal")),
  };
}

// The ground plane.
std::vector<CoreSetting> groundSettings() {
  using C = SegmenterConfig;
  return {
      documented(enumSetting<GroundSource>("ground.source",
                                           [](C& c) -> GroundSource& { return c.ground.source; },
                                           {{"auto", GroundSource::Auto},
                                            {"extrinsics", GroundSource::Extrinsics},
                                            {"floor_labels", GroundSource::FloorLabels},
                                            {"estimated", GroundSource::Estimated},
                                            {"gravity", GroundSource::Gravity}}),
                 "where the ground frame comes from: the camera mount, the estimated floor, floor "
                 "labels or gravity"),
      documented(floatSetting(
                     "ground.ransac_inlier_m",
                     [](C& c) -> float& { return c.ground.ransac_inlier_m; }, 0.001, 0.5),
                 "RANSAC inlier distance of the floor plane fit (m)"),
      documented(intSetting(
                     "ground.ransac_iterations",
                     [](C& c) -> int& { return c.ground.ransac_iterations; }, 1, 100000),
                 "RANSAC iterations of the floor plane fit"),
      documented(intSetting(
                     "ground.min_floor_points",
                     [](C& c) -> int& { return c.ground.min_floor_points; }, 3, 10000000),
                 "fewer floor points than this: no ground plane, the frame is labelled void"),
      documented(floatSetting(
                     "ground.min_inlier_fraction",
                     [](C& c) -> float& { return c.ground.min_inlier_fraction; }, 0.01, 1),
                 "floor_labels: share of floor-labelled points the plane must explain"),
      documented(floatSetting(
                     "ground.normal_agreement_deg",
                     [](C& c) -> float& { return c.ground.normal_agreement_deg; }, 1, 90),
                 "estimated: a point supports a plane only within this angle of its normal (deg)"),
      documented(floatSetting(
                     "ground.min_camera_height_m",
                     [](C& c) -> float& { return c.ground.min_camera_height_m; }, 0, 5),
                 "estimated: the floor must lie at least this far below the camera (m)"),
      documented(floatSetting(
                     "ground.floor_percentile",
                     [](C& c) -> float& { return c.ground.floor_percentile; }, 0, 50),
                 "gravity without floor labels: the floor is no higher than this percentile (%) of "
                 "point heights"),
      documented(
          floatSetting(
              "ground.percentile_margin_m",
              [](C& c) -> float& { return c.ground.percentile_margin_m; }, 0, 5),
          "gravity: ... when it lies more than this (m) below the lowest horizontal surface"),
      documented(floatSetting(
                     "ground.prior_camera_height_m",
                     [](C& c) -> float& { return c.ground.prior_camera_height_m; }, 0.05, 5),
                 "gravity, floor out of view: the camera's height above the floor (m)"),
      documented(floatSetting(
                     "ground.gravity_refine_deg",
                     [](C& c) -> float& { return c.ground.gravity_refine_deg; }, 0, 89),
                 "gravity: a fitted floor plane within this angle (deg) of gravity replaces it; 0 "
                 "= never"),
      documented(
          floatSetting(
              "ground.max_tilt_deg", [](C& c) -> float& { return c.ground.max_tilt_deg; }, 1, 89),
          "estimated: largest angle between the floor normal and the camera's up (deg)"),
      documented(intSetting(
                     "ground.reestimate_every_frames",
                     [](C& c) -> int& { return c.ground.reestimate_every_frames; }, 1, 100000),
                 "a stream from one mount: estimate the floor again at least every this many "
                 "frames; 1 = every frame"),
      documented(floatSetting(
                     "ground.reuse_min_support_fraction",
                     [](C& c) -> float& { return c.ground.reuse_min_support_fraction; }, 0.01, 1),
                 "a stream from one mount: keep an earlier frame's floor while it holds this share "
                 "of its support"),
  };
}

// The oversegmentation into patches.
std::vector<CoreSetting> oversegmentationSettings() {
  using C = SegmenterConfig;
  return {
      recorded(documented(enumSetting<OversegmenterKind>(
                              "oversegmentation.method",
                              [](C& c) -> OversegmenterKind& { return c.oversegmentation.kind; },
                              {{"pcl", OversegmenterKind::PclSupervoxels},
                               {"organized", OversegmenterKind::Organized}}),
                          "how patches are made: pcl (PCL supervoxels, the paper's) or organized "
                          "(image-grid supervoxels, faster)")),
      recorded(documented(
          floatSetting(
              "oversegmentation.voxel_resolution_m",
              [](C& c) -> float& { return c.oversegmentation.voxel_resolution_m; }, 0.001, 1),
          "voxel size of the supervoxel clustering (m)")),
      recorded(documented(
          floatSetting(
              "oversegmentation.seed_resolution_m",
              [](C& c) -> float& { return c.oversegmentation.seed_resolution_m; }, 0.005, 5),
          "spacing of the supervoxel seeds (m): the patch size")),
      recorded(documented(
          floatSetting(
              "oversegmentation.color_importance",
              [](C& c) -> float& { return c.oversegmentation.color_importance; }, 0, 100),
          "weight of colour in the supervoxel distance")),
      recorded(documented(
          floatSetting(
              "oversegmentation.spatial_importance",
              [](C& c) -> float& { return c.oversegmentation.spatial_importance; }, 0, 100),
          "weight of position in the supervoxel distance")),
      recorded(documented(
          floatSetting(
              "oversegmentation.normal_importance",
              [](C& c) -> float& { return c.oversegmentation.normal_importance; }, 0, 100),
          "weight of the normal in the supervoxel distance")),
      recorded(documented(
          intSetting(
              "oversegmentation.min_segment_points",
              [](C& c) -> int& { return c.oversegmentation.min_segment_points; }, 1, 100000),
          "smaller patches are dropped (unreliable features)")),
      recorded(
          documented(intSetting(
                         "oversegmentation.max_iterations",
                         [](C& c) -> int& { return c.oversegmentation.max_iterations; }, 1, 100),
                     "organized: assignment and update rounds")),
      recorded(documented(
          floatSetting(
              "oversegmentation.organized_seed_density",
              [](C& c) -> float& { return c.oversegmentation.organized_seed_density; }, 0.01, 1000),
          "organized: seeds per seed-resolution cell")),
      recorded(documented(
          intSetting(
              "oversegmentation.search_window_factor",
              [](C& c) -> int& { return c.oversegmentation.search_window_factor; }, 1, 10),
          "organized: search window of a seed, in grid steps")),
  };
}

// The feature rows: regions, scene, objects, auto-context.
std::vector<CoreSetting> featureSettings() {
  using C = SegmenterConfig;
  return {
      recorded(documented(
          boolSetting("features.regions", [](C& c) -> bool& { return c.regions.enabled; }),
          "region features: each patch gets the area, extents, height and orientation of its "
          "surface")),
      recorded(documented(
          floatSetting(
              "features.region_normal_angle_deg",
              [](C& c) -> float& { return c.regions.normal_angle_deg; }, 0, 180),
          "neighbouring patches whose normals agree within this angle (deg) may form one surface")),
      recorded(
          documented(floatSetting(
                         "features.region_plane_distance_m",
                         [](C& c) -> float& { return c.regions.plane_distance_m; }, 0, 1),
                     "... and whose centroids lie within this distance (m) of each other's plane")),
      recorded(
          documented(boolSetting("features.scene", [](C& c) -> bool& { return c.scene.enabled; }),
                     "scene features: where a patch sits in the frame's layout")),
      recorded(documented(
          floatSetting(
              "features.scene_cell_m", [](C& c) -> float& { return c.scene.cell_m; }, 0.01, 1),
          "scene features: size of the ground cells and height bins (m)")),
      recorded(documented(
          intSetting(
              "features.scene_band_px", [](C& c) -> int& { return c.scene.band_px; }, 1, 640),
          "scene features: width of the image column band a patch is compared within (px)")),
      recorded(documented(
          boolSetting("features.objects", [](C& c) -> bool& { return c.objects.enabled; }),
          "object features: patches grouped into 3-D object candidates, each patch gets its "
          "object's shape")),
      recorded(documented(
          enumSetting<ObjectColumns>(
              "features.objects_columns", [](C& c) -> ObjectColumns& { return c.objects.columns; },
              objectColumnsWords()),
          "which object feature columns the rows carry: all, context or relations")),
      recorded(documented(
          floatSetting(
              "features.objects_concave_tolerance_deg",
              [](C& c) -> float& { return c.objects.concave_tolerance_deg; }, 0, 90),
          "objects: a concave joint links patches whose normals lie within this angle (deg)")),
      recorded(
          documented(floatSetting(
                         "features.objects_link_gap_m",
                         [](C& c) -> float& { return c.objects.link_gap_m; }, 0, 1),
                     "objects: patches touch when their bounding circles are within this gap (m)")),
      recorded(documented(
          floatSetting(
              "features.objects_step_m", [](C& c) -> float& { return c.objects.step_m; }, 0, 1),
          "objects: a concave joint needs each centroid within this distance (m) of the other's "
          "plane")),
      recorded(
          documented(floatSetting(
                         "features.objects_convex_margin",
                         [](C& c) -> float& { return c.objects.convex_margin; }, 0, 2),
                     "objects: a joint is convex when the normals open by more than this (0..2)")),
      recorded(
          documented(floatSetting(
                         "features.objects_floor_height_m",
                         [](C& c) -> float& { return c.objects.floor_height_m; }, 0, 2),
                     "objects: up-facing patches below this height (m) are floor and stay out")),
      recorded(documented(floatSetting(
                              "features.objects_plane_min_area_m2",
                              [](C& c) -> float& { return c.objects.plane_min_area_m2; }, 0, 100),
                          "objects: walls and ceilings of at least this area (m2) stay out")),
      recorded(
          documented(floatSetting(
                         "features.objects_orientation_tolerance_deg",
                         [](C& c) -> float& { return c.objects.orientation_tolerance_deg; }, 0, 45),
                     "objects: horizontal and vertical mean within this angle (deg)")),
      recorded(documented(
          boolSetting("features.context", [](C& c) -> bool& { return c.context.enabled; }),
          "auto-context: a second forest that also reads the first round's answers around each "
          "patch")),
      recorded(documented(
          floatSetting(
              "features.context_near_m", [](C& c) -> float& { return c.context.near_m; }, 0.01, 10),
          "auto-context: the near ring's radius (m)")),
      recorded(documented(
          floatSetting(
              "features.context_far_m", [](C& c) -> float& { return c.context.far_m; }, 0.01, 10),
          "auto-context: the far ring's radius (m)")),
      recorded(documented(floatSetting(
                              "features.context_column_radius_m",
                              [](C& c) -> float& { return c.context.column_radius_m; }, 0.01, 10),
                          "auto-context: radius (m) of the column above and below a patch")),
      documented(intSetting(
                     "features.context_cross_fit_folds",
                     [](C& c) -> int& { return c.context.cross_fit_folds; }, 0, 100),
                 "training only: groups of frames the first round is cross-fitted over for the "
                 "second round"),
  };
}

// The learner: the random forest, the boosted trees and what both use.
std::vector<CoreSetting> learnerSettings() {
  using C = SegmenterConfig;
  return {
      documented(intSetting(
                     "forest.num_trees", [](C& c) -> int& { return c.forest.num_trees; }, 1, 1000),
                 "trees of the forest (training; a model's own trees are used at run time)"),
      documented(intSetting(
                     "forest.max_depth", [](C& c) -> int& { return c.forest.max_depth; }, 1, 40),
                 "deepest level of a tree (training)"),
      documented(intSetting(
                     "forest.min_samples_leaf",
                     [](C& c) -> int& { return c.forest.min_samples_leaf; }, 1, 1000000),
                 "a node with fewer samples becomes a leaf (training)"),
      documented(
          doubleSetting(
              "forest.shrinkage", [](C& c) -> double& { return c.forest.shrinkage; }, 0, 1e6),
          "hierarchical shrinkage of the leaves towards their ancestors (lambda; 0 = off)"),
      documented(intSetting(
                     "forest.candidate_features",
                     [](C& c) -> int& { return c.forest.candidate_features; }, 1, 1024),
                 "features tried at each split (training)"),
      documented(intSetting(
                     "forest.candidate_thresholds",
                     [](C& c) -> int& { return c.forest.candidate_thresholds; }, 1, 1000),
                 "thresholds tried per feature at each split (training)"),
      documented(enumSetting<LearnerKind>(
                     "learner.kind", [](C& c) -> LearnerKind& { return c.learner.kind; },
                     {{"forest", LearnerKind::Forest}, {"xgboost", LearnerKind::XGBoost}}),
                 "what the model is: forest (the paper's randomized forest) or xgboost; taken from "
                 "the model"),
      documented(enumSetting<ClassScheme>("learner.classes",
                                          [](C& c) -> ClassScheme& { return c.learner.classes; },
                                          {{"labels", ClassScheme::Labels},
                                           {"nyu13", ClassScheme::Nyu13},
                                           {"nyu40", ClassScheme::Nyu40}}),
                 "the classes the model learns, merged into the 8 labels; taken from the model"),
      documented(
          enumSetting<ClassWeight>(
              "learner.class_weight", [](C& c) -> ClassWeight& { return c.learner.class_weight; },
              {{"labels", ClassWeight::Labels}, {"classes", ClassWeight::Classes}}),
          "with internal classes, what class weighting balances: labels or classes"),
      // Both learners train with these; ForestParams carries them to either.
      documented(boolSetting("learner.class_weighting",
                             [](C& c) -> bool& { return c.forest.class_weighting; }),
                 "training: weight each class inversely to its frequency (the paper's)"),
      documented(
          intSetting(
              "learner.num_threads", [](C& c) -> int& { return c.forest.num_threads; }, 0, 256),
          "training threads; 0 = one per core"),
      documented(intSetting(
                     "xgboost.rounds", [](C& c) -> int& { return c.xgboost.rounds; }, 1, 10000),
                 "boosting rounds (learner.kind = xgboost, training)"),
      documented(intSetting(
                     "xgboost.max_depth", [](C& c) -> int& { return c.xgboost.max_depth; }, 1, 30),
                 "deepest level of a boosted tree"),
      documented(doubleSetting(
                     "xgboost.eta", [](C& c) -> double& { return c.xgboost.eta; }, 1e-6, 1),
                 "learning rate of the boosted trees"),
      documented(
          doubleSetting(
              "xgboost.subsample", [](C& c) -> double& { return c.xgboost.subsample; }, 1e-3, 1),
          "share of the rows each boosting round samples"),
      documented(
          doubleSetting(
              "xgboost.colsample", [](C& c) -> double& { return c.xgboost.colsample; }, 1e-3, 1),
          "share of the columns each boosted tree samples"),
      documented(doubleSetting(
                     "xgboost.min_child_weight",
                     [](C& c) -> double& { return c.xgboost.min_child_weight; }, 0, 1e6),
                 "least hessian weight in a boosted tree's child"),
      documented(doubleSetting(
                     "xgboost.lambda", [](C& c) -> double& { return c.xgboost.lambda; }, 0, 1e6),
                 "L2 regularisation of the boosted trees' leaf weights"),
      documented(intSetting(
                     "xgboost.seed", [](C& c) -> int& { return c.xgboost.seed; }, 0, 2147483647),
                 "seed of the boosted trees' training"),
  };
}

// The MRF and the label image.
std::vector<CoreSetting> mrfSettings() {
  using C = SegmenterConfig;
  return {
      documented(boolSetting("mrf.enabled", [](C& c) -> bool& { return c.use_mrf; }),
                 "pairwise MRF over the patch graph (loopy BP); false: the learner's labels only"),
      documented(enumSetting<MrfPairwise>("mrf.pairwise",
                                          [](C& c) -> MrfPairwise& { return c.mrf.pairwise; },
                                          {{"potts", MrfPairwise::Potts},
                                           {"context", MrfPairwise::Context},
                                           {"layout", MrfPairwise::Layout}}),
                 "the pairwise term: potts (the paper's), context (learned per edge, carried by "
                 "the model) or layout (label-layout prior)"),
      documented(
          findmug::textSetting<SegmenterConfig>(
              "mrf.layout_prior_path", [](C& c) -> std::string& { return c.mrf.layout_prior_path; },
              [](const std::string& v) {
                return v.empty() ? std::string("a file path") : std::string();
              }),
          "mrf.pairwise = layout: the label-layout prior file (findmug-learn-layout)"),
      documented(
          floatSetting(
              "mrf.layout_weight", [](C& c) -> float& { return c.mrf.layout_weight; }, 0, 100),
          "mrf.pairwise = layout: weight of the layout costs"),
      documented(floatSetting(
                     "mrf.layout_height_threshold",
                     [](C& c) -> float& { return c.mrf.layout_height_threshold; }, 0, 10),
                 "layout: a neighbour this much higher (m) is the upper one"),
      documented(enumSetting<LayoutDirection>(
                     "mrf.layout_direction",
                     [](C& c) -> LayoutDirection& { return c.mrf.layout_direction; },
                     {{"height", LayoutDirection::Height}, {"image", LayoutDirection::Image}}),
                 "layout: which neighbour is the upper one, by height or by image row"),
      documented(floatSetting(
                     "mrf.layout_image_threshold_px",
                     [](C& c) -> float& { return c.mrf.layout_image_threshold_px; }, 0, 10000),
                 "layout with layout_direction = image: a neighbour this many rows higher (px) is "
                 "the upper one"),
      documented(floatSetting(
                     "mrf.object_consistency",
                     [](C& c) -> float& { return c.mrf.object_consistency; }, 0, 1),
                 "share of each object candidate's mean distribution mixed into its patches' "
                 "unaries, 0..1"),
      documented(floatSetting(
                     "mrf.lambda", [](C& c) -> float& { return c.mrf.lambda; }, 0, 1000),
                 "weight of the unary term against the pairwise one"),
      documented(floatSetting(
                     "mrf.sigma", [](C& c) -> float& { return c.mrf.sigma; }, 1e-4, 100),
                 "distance scale of the pairwise term (m)"),
      documented(
          intSetting(
              "mrf.max_iterations", [](C& c) -> int& { return c.mrf.max_iterations; }, 1, 10000),
          "most loopy BP iterations"),
      documented(floatSetting(
                     "mrf.damping", [](C& c) -> float& { return c.mrf.damping; }, 0, 0.99),
                 "message damping of loopy BP"),
      documented(
          floatSetting(
              "mrf.convergence_tol", [](C& c) -> float& { return c.mrf.convergence_tol; }, 0, 1),
          "loopy BP stops when no message changes more than this"),
      documented(
          boolSetting("labels.fill_holes", [](C& c) -> bool& { return c.label_holes.enabled; }),
          "pixels without depth take the label of the labelled pixels beside them"),
      documented(intSetting(
                     "labels.fill_max_run_px",
                     [](C& c) -> int& { return c.label_holes.max_run_px; }, 1, 10000),
                 "longest run of pixels without depth that is filled (px)"),
  };
}

// Tables and their search positions.
std::vector<CoreSetting> tableSettings() {
  using C = SegmenterConfig;
  return {
      documented(floatSetting(
                     "tables.cluster_tolerance_m",
                     [](C& c) -> float& { return c.tables.cluster_tolerance_m; }, 0.005, 1),
                 "Euclidean clustering distance of table-labelled points (m)"),
      documented(intSetting(
                     "tables.min_cluster_points",
                     [](C& c) -> int& { return c.tables.min_cluster_points; }, 1, 10000000),
                 "smaller clusters are no table"),
      documented(intSetting(
                     "tables.max_cluster_points",
                     [](C& c) -> int& { return c.tables.max_cluster_points; }, 1, 10000000),
                 "larger clusters are no table"),
      documented(
          intSetting(
              "tables.point_stride", [](C& c) -> int& { return c.tables.point_stride; }, 1, 8),
          "clustering and geometry use every point_stride-th pixel of every point_stride-th row; 1 "
          "= all"),
      documented(floatSetting(
                     "tables.safety_distance_m",
                     [](C& c) -> float& { return c.tables.safety_distance_m; }, 0, 5),
                 "search positions: distance from the table edge (m)"),
      documented(
          floatSetting(
              "tables.arm_reach_m", [](C& c) -> float& { return c.tables.arm_reach_m; }, 0.05, 5),
          "search positions: the arm's reach (m)"),
      documented(floatSetting(
                     "tables.robot_radius_m",
                     [](C& c) -> float& { return c.tables.robot_radius_m; }, 0, 3),
                 "search positions: the robot's radius (m)"),
      documented(floatSetting(
                     "tables.min_table_height_m",
                     [](C& c) -> float& { return c.tables.min_table_height_m; }, 0, 3),
                 "table tops lower than this above the floor are ignored (m)"),
      documented(floatSetting(
                     "tables.max_table_height_m",
                     [](C& c) -> float& { return c.tables.max_table_height_m; }, 0, 3),
                 "table tops higher than this above the floor are ignored (m)"),
      documented(
          floatSetting(
              "tables.top_band_m", [](C& c) -> float& { return c.tables.top_band_m; }, 0.005, 0.5),
          "points within this height of the top height form the top (m)"),
      documented(floatSetting(
                     "tables.min_table_width_m",
                     [](C& c) -> float& { return c.tables.min_table_width_m; }, 0, 5),
                 "clusters whose top is narrower than this (m) are dropped"),
      documented(floatSetting(
                     "tables.obstacle_min_height_m",
                     [](C& c) -> float& { return c.tables.obstacle_min_height_m; }, 0, 2),
                 "reachability: obstacle points are at least this high (m)"),
      documented(floatSetting(
                     "tables.robot_height_m",
                     [](C& c) -> float& { return c.tables.robot_height_m; }, 0.1, 3),
                 "reachability: obstacle points are at most this high (m)"),
      documented(intSetting(
                     "tables.obstacle_min_points",
                     [](C& c) -> int& { return c.tables.obstacle_min_points; }, 1, 100000),
                 "reachability: this many obstacle points within the robot's radius block a search "
                 "position"),
      documented(floatSetting(
                     "tables.floor_tolerance_m",
                     [](C& c) -> float& { return c.tables.floor_tolerance_m; }, 0.005, 1),
                 "reachability: floor points lie within this height of the floor (m)"),
      documented(
          floatSetting(
              "tables.floor_cell_m", [](C& c) -> float& { return c.tables.floor_cell_m; }, 0.01, 1),
          "reachability: size of the floor cells marked as seen (m)"),
      documented(floatSetting(
                     "tables.min_floor_observed_fraction",
                     [](C& c) -> float& { return c.tables.min_floor_observed_fraction; }, 0, 1),
                 "reachability: a search position needs at least this share of seen floor under "
                 "the robot"),
      documented(
          boolSetting("tables.region_vote", [](C& c) -> bool& { return c.tables.region_vote; }),
          "one label per horizontal region at table height, by its area-weighted probabilities"),
      documented(floatSetting(
                     "tables.table_weight", [](C& c) -> float& { return c.tables.table_weight; },
                     0.01, 100),
                 "p(table) is multiplied by this in the MRF's unaries; 1 = no bias"),
      documented(floatSetting(
                     "tables.region_max_tilt_deg",
                     [](C& c) -> float& { return c.tables.region_max_tilt_deg; }, 0, 90),
                 "region vote: a region's normal is within this angle of up (deg)"),
      documented(floatSetting(
                     "tables.region_min_area_m2",
                     [](C& c) -> float& { return c.tables.region_min_area_m2; }, 0, 100),
                 "region vote: smallest region that votes (m2)"),
      documented(floatSetting(
                     "tables.min_top_area_m2",
                     [](C& c) -> float& { return c.tables.min_top_area_m2; }, 0, 100),
                 "a table needs a visible top of at least this area (m2)"),
      documented(floatSetting(
                     "tables.min_confidence",
                     [](C& c) -> float& { return c.tables.min_confidence; }, 0, 1),
                 "a table needs at least this mean label confidence"),
      documented(floatSetting(
                     "tables.min_horizontal_share",
                     [](C& c) -> float& { return c.tables.min_horizontal_share; }, 0, 1),
                 "a table needs at least this share of points with a horizontal normal"),
      documented(floatSetting(
                     "tables.horizontal_tilt_deg",
                     [](C& c) -> float& { return c.tables.horizontal_tilt_deg; }, 0, 90),
                 "a normal within this angle of vertical is horizontal (deg)"),
      documented(floatSetting(
                     "tables.soft_top_min_area_m2",
                     [](C& c) -> float& { return c.tables.soft_top_min_area_m2; }, 0, 100),
                 "table-top test: tops at least this large (m2) must be flat to be a table"),
      documented(
          floatSetting(
              "tables.flat_tilt_deg", [](C& c) -> float& { return c.tables.flat_tilt_deg; }, 0, 90),
          "table-top test: a horizontal normal within this angle of vertical (deg) is flat"),
      documented(floatSetting(
                     "tables.min_flat_share",
                     [](C& c) -> float& { return c.tables.min_flat_share; }, 0, 1),
                 "table-top test: a large top needs at least this share of flat normals"),
      documented(boolSetting("tables.relabel_soft_tops",
                             [](C& c) -> bool& { return c.tables.relabel_soft_tops; }),
                 "label a large top that is not flat (a bed, a sofa) Unknown"),
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
      documented(seedSetting("forest.seed", [](C& c) -> std::uint64_t& { return c.forest.seed; }),
                 "seed of the forest's training"),
      baggingFractionSetting(),
      documented(seedSetting("ground.seed", [](C& c) -> std::uint64_t& { return c.ground.seed; }),
                 "seed of the floor plane fit's random samples"),
  };
}

const std::vector<CoreSetting>& segmenterSettingList() {
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

}  // namespace
}  // namespace settings_internal

const SettingsTable<SegmenterConfig>& segmenterSettings() {
  static const SettingsTable<SegmenterConfig> table =
      settings_internal::tableOf(settings_internal::segmenterSettingList());
  return table;
}

}  // namespace findmug
