// findmug/settings/offline_settings.hpp — the settings only the offline tools read:
// how a training set is built (training.*), the raw-depth model of training and
// evaluation (degrade.*), findmug-eval's table metrics (table_metrics.*).
//
// Plain data and their settings table, here and not beside their code in
// findmug/offline/, because every program sharing daemon/findmugd.yaml checks these
// sections too (a typo in training: is refused by findmugd as well); the code that
// uses them lives in the offline library, which the daemon does not link. None of it
// is in SegmenterConfig: what a frame goes through at run time does not depend on it.
#pragma once

#include <cstdint>

#include "findmug/settings/settings.hpp"

namespace findmug {

struct SegmenterConfig;

// How the forest's training set is built from labelled frames (training.*;
// findmug-train, findmug-eval's cross-validation): a model does not depend on
// them at run time, so they are not recorded as extraction settings.
enum class SampleWeighting {
  Patches,     // one vote per patch (the paper's)
  Pixels,      // each patch weighs its pixel count: the figures are per pixel
  SqrtPixels,  // in between: large patches count more, but not in proportion
};
// The classes the forest's splits are chosen by (training.split_labels).
enum class SplitLabels {
  Labels,  // the 8 findmug classes the leaves hold (the paper's)
  Nyu40,   // the NYU-40 class of each patch (needs label40/ or the .mat file):
           // "cabinet", "object" and "unknown" each gather unlike things, and
           // splits that tell those apart can help the 8-class answer
  Nyu13,   // the NYU-13 class of each patch (needs label13/): fewer, larger
           // classes (books / objects / tv, bed / sofa, wall / window / picture)
};

struct TrainingOptions {
  SampleWeighting sample_weight = SampleWeighting::Patches;  // training.sample_weight
  SplitLabels split_labels = SplitLabels::Labels;            // training.split_labels
  // Augmentation: each training frame also contributes the patches of this
  // many other oversegmentations (training.extra_oversegmentations), the k-th
  // with oversegmentation.seed_resolution_m scaled by extra_seed_scale^j, j = 1, -1,
  // 2, -2, ... (training.extra_seed_scale): more and more varied patches per
  // frame. Evaluation and the daemon still use the configured one only.
  int extra_oversegmentations = 0;
  float extra_seed_scale = 0.8f;
  // Augmentation: each training frame also contributes the patches of this
  // many raw-like copies of it (degradeDepth with degrade.*, copy k with seed
  // degraded_seed + k; training.degraded_copies, training.degraded_seed).
  int degraded_copies = 0;
  std::uint64_t degraded_seed = 7;
  // Semi-supervised rounds (findmug/offline/pseudo_labels.hpp; findmug-train and
  // findmug-eval --unlabelled DIR): train, label the unlabelled frames with
  // the whole Segmenter (forest + MRF + table region vote), keep the patches
  // whose confidence exceeds pseudo_min_confidence as training patches of
  // weight pseudo_weight, at most pseudo_class_cap times the labelled patches
  // of the same label per label (the most confident first), retrain; this
  // many times (training.pseudo_rounds, 0 = off).
  int pseudo_rounds = 0;
  float pseudo_min_confidence = 0.8f;
  float pseudo_weight = 1.0f;
  float pseudo_class_cap = 1.0f;
};


// table_metrics.*: how findmug-eval matches detected tables with ground-truth instances
// (findmug/offline/table_metrics.hpp).
struct TableMetricsConfig {
  int min_instance_points = 1000;  // smaller ground-truth table components are not instances
  float min_iou = 0.5f;            // image-mask IoU for a detection to match an instance
  // "Searchable" tables (findmug/offline/table_metrics.hpp, measureSearchableTables).
  float searchable_min_top_area_m2 = 0.15f;  // a true table's visible top at least this
  float searchable_min_overlap = 0.5f;       // top overlap for a detection to match a table
  float searchable_max_height_error_m = 0.15f;  // and their top heights at most this apart
};

// The model's parameters (settings degrade.*). Defaults are calibrated on
// NYU frame 0433's raw depth, nyuv2_raw_basement3 and the Bonn Kinect
// frames (docs/measurements/raw-depth-and-context.md).
struct DepthDegradationConfig {
  // Projector-camera baseline (m) and focal length (px) of the shadow model:
  // a background pixel is shadowed when a nearer surface hides it from the
  // projector; the shadow is f*b*(1/z_near - 1/z_far) px wide, on the left
  // of near objects for b > 0 (the Kinect's layout), on the right for b < 0;
  // 0 turns shadows off.
  float shadow_baseline_m = 0.075f;
  float shadow_focal_px = 580.0f;
  // A depth edge: neighbouring depths differing by more than this fraction
  // of the nearer one. Pixels within edge_band_px of one drop out with
  // edge_hole_probability each.
  float edge_relative_jump = 0.04f;
  int edge_band_px = 1;
  float edge_hole_probability = 0.3f;
  // Dropout chance of every pixel, plus a ramp on dark pixels (grey value
  // below dark_level: up to dark_hole_probability at black), on saturated
  // ones (grey above bright_level: up to bright_hole_probability at white,
  // specular highlights and windows) and with range (far_hole_per_m per metre
  // beyond far_start_m).
  float base_hole_probability = 0.04f;
  float dark_level = 100.0f;
  float dark_hole_probability = 0.2f;
  float bright_level = 235.0f;
  float bright_hole_probability = 0.6f;
  float far_start_m = 4.5f;
  float far_hole_per_m = 0.03f;
  // Dropouts come in blobs about this wide (px): the chance above is
  // compared with spatially correlated noise. 0: independent pixels.
  float blob_size_px = 32.0f;
  // Kinect disparity: depth_m = 351.3 / (1092.5 - d), d an integer in raw
  // units. Gaussian noise of this standard deviation (raw units) is added to
  // d before it is rounded; quantise = false keeps depth continuous (and
  // noise-free when the noise is 0 as well).
  bool quantise = true;
  float disparity_noise = 0.35f;
  // A frame that already has more holes than this share of the pixels
  // inside the bounding box of its measured ones (a masked border is not a
  // hole) is raw depth already (NYU 0433, a live camera): returned unchanged.
  float max_input_hole_fraction = 0.05f;
};

struct OfflineConfig {
  TrainingOptions training;          // training.*
  DepthDegradationConfig degrade;    // degrade.*
  TableMetricsConfig table_metrics;  // table_metrics.*
};

// The sections training, degrade and table_metrics: one table.
const SettingsTable<OfflineConfig>& offlineSettings();
// The rule between them and the segmenter's settings (learner.classes cannot be
// combined with training.split_labels); throws Error naming the keys.
void validateOfflineConfig(const OfflineConfig& offline, const SegmenterConfig& segmenter);

}  // namespace findmug
