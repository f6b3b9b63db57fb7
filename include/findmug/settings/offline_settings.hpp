// findmug/settings/offline_settings.hpp — the settings tables that only the offline tools
// read (findmug-eval's table metrics, the raw-depth model of training and evaluation).
//
// Plain data, here and not beside their code in findmug/offline/, because the settings
// (findmug/settings/config.hpp) parse every table of the project; the code that uses them
// lives in the offline library, which the daemon does not link.
#pragma once

namespace findmug {

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

}  // namespace findmug
