// offline_settings.cpp — the offline tools' settings table (offlineSettings,
// findmug/settings/offline_settings.hpp): training.*, degrade.*, table_metrics.*.
#include "findmug/settings/offline_settings.hpp"

#include <cstdint>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/settings/config.hpp"
#include "settings/setting_builders_internal.hpp"

namespace findmug {

// Inside settings_internal, so that its builders hide the mechanism's of the same name.
namespace settings_internal {
namespace {

// The offline tools' settings (offline_settings.hpp).
const std::vector<Setting<OfflineConfig>>& offlineSettingList() {
  using O = OfflineConfig;
  static const std::vector<Setting<OfflineConfig>> all = {
      documented(enumSetting<SampleWeighting, O>(
                     "training.sample_weight",
                     [](O& c) -> SampleWeighting& { return c.training.sample_weight; },
                     {{"patches", SampleWeighting::Patches},
                      {"pixels", SampleWeighting::Pixels},
                      {"sqrt_pixels", SampleWeighting::SqrtPixels}}),
                 "what each training patch weighs: patches, pixels or sqrt_pixels"),
      documented(
          enumSetting<SplitLabels, O>("training.split_labels",
                                      [](O& c) -> SplitLabels& { return c.training.split_labels; },
                                      {{"labels", SplitLabels::Labels},
                                       {"nyu40", SplitLabels::Nyu40},
                                       {"nyu13", SplitLabels::Nyu13}}),
          "the classes the forest's splits are chosen by: labels, nyu40 or nyu13 (leaves keep the "
          "8 labels)"),
      documented(intSetting<O>(
                     "training.extra_oversegmentations",
                     [](O& c) -> int& { return c.training.extra_oversegmentations; }, 0, 8),
                 "augmentation: also train on this many other oversegmentations of every frame"),
      documented(floatSetting<O>(
                     "training.extra_seed_scale",
                     [](O& c) -> float& { return c.training.extra_seed_scale; }, 0.3, 0.99),
                 "augmentation: the seed resolution scale between those oversegmentations"),
      documented(
          intSetting<O>(
              "training.degraded_copies", [](O& c) -> int& { return c.training.degraded_copies; },
              0, 8),
          "augmentation: also train on this many raw-like copies of every frame (degrade.*)"),
      documented(intSetting<O>(
                     "training.pseudo_rounds",
                     [](O& c) -> int& { return c.training.pseudo_rounds; }, 0, 10),
                 "semi-supervised rounds on the unlabelled frames (--unlabelled)"),
      documented(floatSetting<O>(
                     "training.pseudo_min_confidence",
                     [](O& c) -> float& { return c.training.pseudo_min_confidence; }, 0, 1),
                 "semi-supervised: patches whose MRF belief is at most this are left out"),
      documented(floatSetting<O>(
                     "training.pseudo_weight",
                     [](O& c) -> float& { return c.training.pseudo_weight; }, 0.001, 1),
                 "semi-supervised: weight of a pseudo-labelled training patch, (0, 1]"),
      documented(floatSetting<O>(
                     "training.pseudo_class_cap",
                     [](O& c) -> float& { return c.training.pseudo_class_cap; }, 0, 1000),
                 "semi-supervised: most pseudo-labelled patches per label, as a multiple of the "
                 "labelled frames' ones"),
      // 64-bit: parsed as an integer, never through a double.
      documented(seedSetting<O>("training.degraded_seed",
                                [](O& c) -> std::uint64_t& { return c.training.degraded_seed; }),
                 "seed of the first degraded copy (copy k: seed + k)"),
      documented(floatSetting<O>(
                     "degrade.shadow_baseline_m",
                     [](O& c) -> float& { return c.degrade.shadow_baseline_m; }, -0.5, 0.5),
                 "projector shadow: baseline (m; > 0 shadows left of near objects, 0 none)"),
      documented(floatSetting<O>(
                     "degrade.shadow_focal_px",
                     [](O& c) -> float& { return c.degrade.shadow_focal_px; }, 1, 5000),
                 "projector shadow: focal length (px)"),
      documented(floatSetting<O>(
                     "degrade.edge_relative_jump",
                     [](O& c) -> float& { return c.degrade.edge_relative_jump; }, 0.001, 10),
                 "depth edges: neighbours differing by this share of the nearer depth"),
      documented(
          intSetting<O>(
              "degrade.edge_band_px", [](O& c) -> int& { return c.degrade.edge_band_px; }, 0, 32),
          "depth edges: pixels within this band (px) may drop out"),
      documented(floatSetting<O>(
                     "degrade.edge_hole_probability",
                     [](O& c) -> float& { return c.degrade.edge_hole_probability; }, 0, 1),
                 "depth edges: the chance such a pixel drops out"),
      documented(floatSetting<O>(
                     "degrade.base_hole_probability",
                     [](O& c) -> float& { return c.degrade.base_hole_probability; }, 0, 1),
                 "the chance any pixel drops out"),
      documented(
          floatSetting<O>(
              "degrade.dark_level", [](O& c) -> float& { return c.degrade.dark_level; }, 0, 255),
          "grey level below which dark pixels drop out more often"),
      documented(floatSetting<O>(
                     "degrade.dark_hole_probability",
                     [](O& c) -> float& { return c.degrade.dark_hole_probability; }, 0, 1),
                 "the chance a black pixel drops out"),
      documented(floatSetting<O>(
                     "degrade.bright_level", [](O& c) -> float& { return c.degrade.bright_level; },
                     0, 254),
                 "grey level above which saturated pixels drop out more often"),
      documented(floatSetting<O>(
                     "degrade.bright_hole_probability",
                     [](O& c) -> float& { return c.degrade.bright_hole_probability; }, 0, 1),
                 "the chance a white pixel drops out"),
      documented(
          floatSetting<O>(
              "degrade.far_start_m", [](O& c) -> float& { return c.degrade.far_start_m; }, 0, 20),
          "far pixels drop out more often from this depth (m)"),
      documented(floatSetting<O>(
                     "degrade.far_hole_per_m",
                     [](O& c) -> float& { return c.degrade.far_hole_per_m; }, 0, 10),
                 "the added chance of dropping out per metre beyond far_start_m"),
      documented(floatSetting<O>(
                     "degrade.blob_size_px", [](O& c) -> float& { return c.degrade.blob_size_px; },
                     0, 200),
                 "dropouts come in blobs of about this size (px)"),
      documented(
          boolSetting<O>("degrade.quantise", [](O& c) -> bool& { return c.degrade.quantise; }),
          "integer Kinect disparity with noise before rounding"),
      documented(floatSetting<O>(
                     "degrade.disparity_noise",
                     [](O& c) -> float& { return c.degrade.disparity_noise; }, 0, 20),
                 "Gaussian disparity noise (raw units)"),
      documented(floatSetting<O>(
                     "degrade.max_input_hole_fraction",
                     [](O& c) -> float& { return c.degrade.max_input_hole_fraction; }, 0, 1),
                 "frames with more holes than this share are raw already and left as they are"),
      documented(intSetting<O>(
                     "table_metrics.min_instance_points",
                     [](O& c) -> int& { return c.table_metrics.min_instance_points; }, 1, 10000000),
                 "findmug-eval: ground-truth tables are components of at least this many points"),
      documented(
          floatSetting<O>(
              "table_metrics.min_iou", [](O& c) -> float& { return c.table_metrics.min_iou; }, 0.01,
              1),
          "findmug-eval: a detection matches a table when their masks have at least this IoU"),
      documented(
          floatSetting<O>(
              "table_metrics.searchable_min_top_area_m2",
              [](O& c) -> float& { return c.table_metrics.searchable_min_top_area_m2; }, 0, 100),
          "findmug-eval: searchable tables have a visible top of at least this area (m2)"),
      documented(
          floatSetting<O>(
              "table_metrics.searchable_min_overlap",
              [](O& c) -> float& { return c.table_metrics.searchable_min_overlap; }, 0.01, 1),
          "findmug-eval: ... matched by a top hull overlapping at least this share"),
      documented(
          floatSetting<O>(
              "table_metrics.searchable_max_height_error_m",
              [](O& c) -> float& { return c.table_metrics.searchable_max_height_error_m; }, 0, 10),
          "findmug-eval: ... with top heights at most this far apart (m)"),
  };
  return all;
}

}  // namespace
}  // namespace settings_internal

const SettingsTable<OfflineConfig>& offlineSettings() {
  static const SettingsTable<OfflineConfig> table =
      settings_internal::tableOf(settings_internal::offlineSettingList());
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

}  // namespace findmug
