// findmug-eval: accuracy of the forest and forest+MRF on a labelled dataset.
//
//   findmug-eval (--data DIR | --mat FILE)... [--folds 5] [--folds-by auto|scenes|blocks]
//                [--model MODEL] [--json FILE] [--out DIR] [--sweep] [--train-extra DIR ...]
//                [--train-frames N --subset-seed S] [--learning-curve DIR]
//                [--config FILE] [--set key=value ...]
//
// Without --model: k-fold cross-validation by frame, over the frames of every
// --data folder and --mat file together. Folds hold whole scenes
// (cv_folds.hpp: a frames.csv `scene` column, else NYU index runs) where every
// frame's scene is known, else contiguous blocks of frames (--folds-by).
// --train-frames trains each fold on N of its training frames (whole scenes
// where possible), --learning-curve repeats the CV over several N and seeds
// and writes a CSV and an SVG with a fitted a + b ln N trend. With
// --model: that model on every frame. Reports per-class, class-average and
// global accuracy (void excluded) for the forest alone and with the MRF, a
// confusion-matrix heatmap, optional sweeps over trees and depth (the
// paper's Fig. 3), and colour overlays of prediction vs ground truth. Tables
// are measured as objects too (table_metrics.hpp): instance precision and
// recall of the tables found on the forest+MRF labels, and the height,
// centroid and axis errors of the matched ones. On synthetic folders
// (findmug-synth's ground_truth.yaml) also the search positions against the
// true tables': position and yaw error to the nearest true position, and the
// share of predicted positions where the robot fits in the true scene.
// --train-extra adds a data set (e.g. synthetic scenes) to the training set
// of every fold; it is never evaluated, so figures stay comparable.
// --degrade evaluates on raw-like copies of the frames (depth_degradation.hpp,
// degrade.* settings) while training stays on the frames as they are;
// The depth holes take their neighbours' labels as the daemon's label image
// does (labels.fill_holes); --score-labelled-only leaves the pixels without
// a patch (depth holes) out of the figures instead.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "eval_cv.hpp"
#include "eval_report.hpp"
#include "eval_table_measures.hpp"
#include "eval_tables.hpp"
#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/offline/cv_folds.hpp"
#include "findmug/offline/metrics.hpp"
#include "findmug/offline/pseudo_labels.hpp"
#include "findmug/offline/table_metrics.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/synth/synth.hpp"
#include "findmug/tables/table_regions.hpp"
#include "findmug_cli.hpp"
#include "tool_common.hpp"

namespace findmug::tools {
namespace {

// Shown by --help above the flag list.
constexpr const char* kDescription =
    "Cross-validates (default 5 folds) or evaluates --model on labelled frames: every --data\n"
    "DIR and --mat nyu_depth_v2_labeled.mat given, together. --nyu-rotations gives NYU frames\n"
    "their gravity (for --set ground.source=gravity).\n"
    "Folds (--folds-by auto): whole scenes when every frame's scene is known, else contiguous\n"
    "blocks of frames in input order (folders in the order given, frames by name). A frame's\n"
    "scene is the `scene` column of its folder's frames.csv; else, for NYU frames (frames.csv\n"
    "with `nyu_index`, or --mat): with --nyu-split, a run of consecutive NYU indices on one side\n"
    "of NYU's scene-disjoint train/test split; without it, frames sorted by NYU index form one\n"
    "scene while each index is at most --scene-gap (2) above the previous one (NYU stores its\n"
    "labelled frames scene by scene; with frames missing this can split a room). Scenes go to\n"
    "folds largest first, each into the fold with the fewest frames so far (ties: the lower\n"
    "fold). The text and JSON reports list every fold's test frames and scenes.";

struct EvalFlags {
  DatasetFlags dataset;
  std::string model, json, out, table_report, table_evidence, curve_dir, nyu_split;
  std::string folds_by = "auto";
  std::string curve_sizes = "5,10,20,30,all";
  int folds = 5, scene_gap = 2, train_frames = 0, curve_seeds = 3;
  std::uint64_t subset_seed = 0;
  bool sweep = false;
  bool degrade = false, score_labelled_only = false;
  std::uint64_t degrade_seed = 1;
  std::vector<std::string> train_extra;
  std::vector<std::string> unlabelled;
  cli::ConfigFlags config;
};

// The flags of findmug-eval; a value given twice: the last wins.
std::unique_ptr<CLI::App> makeEvalApp(EvalFlags& f) {
  auto app = cli::makeApp("findmug-eval", kDescription);
  auto last = [](CLI::Option* o) {
    return o->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  };
  addDatasetFlags(*app, f.dataset);
  last(app->add_option("--folds", f.folds, "cross-validation folds (see --folds-by)")
           ->type_name("K")
           ->check(CLI::Validator(
               [](std::string& text) -> std::string {
                 const auto folds = parseInteger(text);
                 if (folds && *folds >= 2 && *folds <= std::numeric_limits<int>::max()) return {};
                 return "must be an integer >= 2, got '" + text + "'";
               },
               "INTEGER >= 2")));
  cli::addModelFlag(*app, f.model,
                    "evaluate this model on every frame instead of cross-validating");
  last(app->get_option("--model"));
  last(app->add_option("--json", f.json, "also write the report as JSON")->type_name("FILE"));
  last(app->add_option("--out", f.out,
                       "folder for the pictures (confusion heatmaps, sweeps, overlays)")
           ->type_name("DIR"));
  app->add_flag("--sweep", f.sweep, "also cross-validate over tree count and depth (paper Fig. 3)");
  app->add_option("--train-extra", f.train_extra,
                  "dataset folder added to every fold's training set, never evaluated (repeatable)")
      ->type_name("DIR")
      ->allow_extra_args(false);
  addUnlabelledFlag(*app, f.unlabelled);
  cli::addConfigFlags(*app, f.config, "YAML config (segmenter settings)");
  last(app->add_option("--folds-by", f.folds_by,
                       "scenes: whole scenes per fold; blocks: contiguous blocks of frames; "
                       "auto (default): scenes when every frame's scene is known")
           ->type_name("RULE")
           ->check(CLI::IsMember({"auto", "scenes", "blocks"})));
  last(app->add_option("--scene-gap", f.scene_gap,
                       "NYU frames whose indices are at most this far apart are one scene")
           ->type_name("N")
           ->check(CLI::Range(0, 1449)));
  last(app->add_option("--nyu-split", f.nyu_split,
                       "NYU's official test indices (nyuv2_meta/split_test_indices.txt): NYU "
                       "frames' scenes are runs of the split (see above)")
           ->type_name("FILE"));
  last(app->add_option("--train-frames", f.train_frames,
                       "train each fold on only N of its training frames (whole scenes where "
                       "possible; 0 = all)")
           ->type_name("N")
           ->check(CLI::Range(0, 1000000)));
  last(app->add_option("--subset-seed", f.subset_seed,
                       "seed choosing the --train-frames subset (fold k uses S + k)")
           ->type_name("S"));
  last(app->add_option("--learning-curve", f.curve_dir,
                       "also cross-validate with --curve-sizes training frames x --curve-seeds "
                       "seeds; write learning_curve.csv, learning_curve_trend.csv and "
                       "learning_curve.svg to DIR")
           ->type_name("DIR"));
  last(app->add_option("--curve-sizes", f.curve_sizes,
                       "training frames per fold for --learning-curve (comma-separated; 'all')")
           ->type_name("LIST"));
  last(app->add_option("--curve-seeds", f.curve_seeds,
                       "seeds per size for --learning-curve: seed s uses subset seed s and "
                       "forest.seed + 1000 s")
           ->type_name("K")
           ->check(CLI::Range(1, 100)));
  last(app->add_option("--table-evidence", f.table_evidence,
                       "write a CSV of every detected table's top measures (height, size, "
                       "flatness, normals, what is under it) with its true NYU-40 class")
           ->type_name("FILE"));
  last(app->add_option("--table-report", f.table_report,
                       "write a per-frame diagnosis of table instances and detections "
                       "(why each unmatched one failed) to FILE")
           ->type_name("FILE"));
  app->add_flag("--degrade", f.degrade,
                "evaluate on raw-like copies of the frames (degrade.* settings); training "
                "uses the frames as they are");
  last(app->add_option("--degrade-seed", f.degrade_seed, "seed of the --degrade copies")
           ->type_name("N"));
  app->add_flag("--score-labelled-only", f.score_labelled_only,
                "score only pixels the Segmenter labelled (leave depth holes out)");
  return app;
}

// Tables found on each evaluated frame's forest+MRF labels (the Segmenter's
// detectTables) against the ground-truth instances. The frame's geometry is
// recomputed (cloud, ground): cheap, and it keeps FrameSample small.
// On synthetic folders (`synth` = their ground_truth.yaml) also the search
// positions of the detected tables against those of the true tables.
// With `diagnosis`, each frame's instances and detections are described
// there, with why each unmatched one failed (eval_tables.hpp).
void measureTables(const LabeledFrames& frames, const std::vector<FrameSample>& samples,
                   Evaluation& eval, const Segmenter& segmenter, const TableMetricsConfig& metrics,
                   const synth::SequenceGroundTruth* synth, EvalReport& report,
                   std::ostream* diagnosis, const TableEvidenceOut& evidence = {}) {
  const SegmenterConfig& config = segmenter.config();
  std::map<std::string, std::size_t> pose_of;
  if (synth) {
    for (std::size_t i = 0; i < synth->frame_names.size(); ++i) pose_of[synth->frame_names[i]] = i;
  }
  bool relabelled = false;
  for (std::size_t f = 0; f < samples.size(); ++f) {
    if (eval.mrf_pixels[f].empty()) continue;
    LabeledFrame frame = frames.load(samples[f].source_index);
    const PreparedFrame prepared = segmenter.prepare(std::move(frame.frame), &frame.labels);
    if (!prepared.ground) {
      throw Error(samples[f].name + ": no ground plane on the second pass (was found before)");
    }
    // The truth is clustered with the built-in table settings, not the
    // evaluated ones: a sweep of tables.* then moves the detections only.
    const auto truth =
        groundTruthTables(prepared.cloud_ground, samples[f].ground_truth, TableConfig{}, metrics);
    const FrameSample& sample = samples[f];
    std::vector<float> table_probability(sample.pixel_segment.size(), 0.0f);
    std::vector<float> confidence(sample.pixel_segment.size(), 0.0f);
    for (std::size_t p = 0; p < sample.pixel_segment.size(); ++p) {
      const int s = sample.pixel_segment[p];
      if (s < 0) continue;
      table_probability[p] =
          eval.probabilities[f][static_cast<std::size_t>(s)][static_cast<int>(Label::Table)];
      confidence[p] = eval.mrf_results[f].confidence[static_cast<std::size_t>(s)];
    }
    LabelImage predicted{sample.width, sample.height, eval.mrf_pixels[f], confidence};
    const TableDetection detection =
        detectTables(prepared.cloud_ground, predicted, config.tables, &prepared.normals_ground);
    const std::vector<TableCluster>& detected = detection.tables;
    const auto matches = matchTables(truth, detected, metrics.min_iou);
    if (evidence.csv) {
      const std::vector<std::uint8_t> truth40 =
          nyu40Labels(*evidence.folders, sample.name, sample.pixel_segment.size());
      const std::vector<std::uint8_t>* fine = truth40.empty() ? nullptr : &truth40;
      auto write = [&](const char* source, const std::vector<TableCluster>& tables) {
        for (const TableCluster& t : tables)
          writeTableEvidence(
              *evidence.csv, source,
              measureTableTop(sample.name, prepared.cloud_ground, prepared.normals_ground, t,
                              config.tables.top_band_m, fine));
      };
      write("detected", detected);
      // Every cluster of the predicted table pixels, before the top-area and horizontal
      // filters, and every true instance of the candidate classes clustered as if it were
      // labelled table (NYU-40: 3 cabinet, 4 bed, 5 chair, 6 sofa, 7 table, 12 counter,
      // 14 desk, 17 dresser, 32 night stand, 39 otherfurniture).
      TableConfig loose = config.tables;
      loose.min_top_area_m2 = 0.0f;
      loose.min_horizontal_share = 0.0f;
      loose.min_flat_share = 0.0f;
      write("predicted-all",
            detectTables(prepared.cloud_ground, predicted, loose, &prepared.normals_ground).tables);
      if (fine && evidence.truth) {
        for (int c : {3, 4, 5, 6, 7, 12, 14, 17, 32, 39}) {
          LabelImage as_table{
              sample.width, sample.height, std::vector<std::uint8_t>(truth40.size(), 0), {}};
          for (std::size_t p = 0; p < truth40.size(); ++p)
            if (truth40[p] == c) as_table.labels[p] = static_cast<std::uint8_t>(Label::Table);
          write("truth",
                detectTables(prepared.cloud_ground, as_table, loose, &prepared.normals_ground)
                    .tables);
        }
      }
    }
    // The pipeline's tables.relabel_soft_tops: a cluster that failed the table-top test is
    // labelled Unknown, in the frame's final labels. (The pipeline relabels before the label
    // holes are filled, these labels are filled already: pixels without depth are in no
    // cluster and keep their filled label here.)
    if (config.tables.relabel_soft_tops && relabelSoftTops(detection, predicted) > 0) {
      eval.mrf_pixels[f] = predicted.labels;
      relabelled = true;
    }
    measureRelabel(prepared, predicted, detected, sample.ground_truth, config, report.relabel);
    if (diagnosis) {
      const FrameTableEvidence evidence{
          sample.name,         sample.width,       sample.height,           &sample.ground_truth,
          &eval.mrf_pixels[f], &table_probability, &prepared.normals_ground};
      *diagnosis << diagnoseFrameTables(evidence, truth, detected, matches, report.diagnosis);
    }
    report.tables.add(static_cast<int>(truth.size()), static_cast<int>(detected.size()), matches);
    report.searchable.add(measureSearchableTables(truth, detected, metrics));
    {
      std::vector<bool> matched(detected.size(), false);
      for (const auto& m : matches) matched[static_cast<std::size_t>(m.detected)] = true;
      for (std::size_t d = 0; d < detected.size(); ++d) {
        report.scored_tables.push_back({detected[d].mean_confidence, matched[d]});
      }
    }
    report.frame_tables.push_back({samples[f].name, static_cast<int>(truth.size()),
                                   static_cast<int>(detected.size()),
                                   static_cast<int>(matches.size())});
    if (!synth) continue;
    const auto pose = pose_of.find(samples[f].name);
    if (pose == pose_of.end()) {
      throw Error(frames.description + ": frame " + samples[f].name +
                  " is not in ground_truth.yaml");
    }
    std::vector<SearchPosition> true_positions;
    for (const auto& table : synth->tables) {
      const synth::TableTruth t = synth::tableInGroundFrame(table, synth->poses[pose->second]);
      const auto p =
          searchPositionsOfBox(t.center_xy.cast<float>(), static_cast<float>(t.yaw),
                               t.size.cast<float>(), static_cast<float>(t.height), config.tables);
      true_positions.insert(true_positions.end(), p.begin(), p.end());
    }
    std::vector<SearchPosition> predicted_positions;
    for (const auto& table : detected) {
      predicted_positions.insert(predicted_positions.end(), table.search_positions.begin(),
                                 table.search_positions.end());
    }
    // Reachable in the ground truth: the robot, at the position in the world,
    // clear of the walls and of every furniture footprint. Files without
    // obstacles (older findmug-synth) still have the table tops.
    const synth::CameraPose& camera = synth->poses[pose->second];
    const Eigen::Isometry3d ground_to_world = synth::worldToGround(camera).inverse();
    std::vector<synth::Obstacle> obstacles = synth->obstacles;
    if (obstacles.empty()) {
      for (const auto& table : synth->tables)
        obstacles.push_back({table.top_polygon, table.height, 0});
    }
    std::vector<bool> flagged, truly;
    for (const auto& p : predicted_positions) {
      const Eigen::Vector3d world = ground_to_world * Eigen::Vector3d(p.xy.x(), p.xy.y(), 0.0);
      flagged.push_back(p.reachable);
      truly.push_back(synth::robotFits(synth->room_size, obstacles, world.head<2>(),
                                       config.tables.robot_radius_m));
    }
    report.search.add(nearestPositionErrors(predicted_positions, true_positions), flagged, truly);
    report.has_search_truth = true;
  }
  // The "+MRF" figures are of the final labels: counted again with the soft tops relabelled.
  if (relabelled) {
    eval.mrf = ConfusionMatrix{};
    for (std::size_t f = 0; f < samples.size(); ++f)
      if (!eval.mrf_pixels[f].empty()) eval.mrf.add(samples[f].ground_truth, eval.mrf_pixels[f]);
  }
}

void writeOverlays(const LabeledFrames& frames, const std::vector<FrameSample>& samples,
                   const Evaluation& eval, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  for (std::size_t f = 0; f < samples.size(); ++f) {
    if (eval.mrf_pixels[f].empty()) continue;
    const LabeledFrame frame = frames.load(samples[f].source_index);
    const int w = frame.frame.width, h = frame.frame.height;
    LabelImage truth{w, h, samples[f].ground_truth, {}};
    LabelImage predicted{w, h, eval.mrf_pixels[f], {}};
    const auto truth_rgb = colorizeLabels(truth, frame.frame.rgb, 0.7f);
    const auto predicted_rgb = colorizeLabels(predicted, frame.frame.rgb, 0.7f);
    // Side by side: colour | ground truth | prediction.
    Image<Rgb8> out{3 * w, h, std::vector<Rgb8>(static_cast<std::size_t>(3) * w * h)};
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t src = static_cast<std::size_t>(y) * w + x;
        const std::size_t row = static_cast<std::size_t>(y) * 3 * w;
        out.pixels[row + x] = frame.frame.rgb[src];
        out.pixels[row + w + x] = truth_rgb[src];
        out.pixels[row + 2 * w + x] = predicted_rgb[src];
      }
    }
    writePngRgb((dir / (samples[f].name + ".png")).string(), out);
  }
}

// Each sample's fold and scene for the --folds-by rule.
FoldPlan planFolds(const EvalFlags& f, const LabeledInputs& input,
                   const std::vector<FrameSample>& samples) {
  std::optional<std::vector<long>> test_indices;
  if (!f.nyu_split.empty()) test_indices = loadNyuTestIndices(f.nyu_split);
  const std::vector<std::string> scenes =
      input.scenes(f.scene_gap, test_indices ? &*test_indices : nullptr);
  FoldPlan plan;
  plan.folds = f.folds;
  std::vector<std::string> missing;
  for (const FrameSample& s : samples) {
    const std::string& scene = scenes[s.source_index];
    if (scene.empty()) missing.push_back(s.name);
    plan.scene_of_sample.push_back(scene.empty() ? "frame:" + s.name : scene);
  }
  plan.rule = f.folds_by == "auto" ? (missing.empty() ? "scenes" : "blocks") : f.folds_by;
  if (plan.rule == "scenes" && !missing.empty()) {
    throw Error("--folds-by scenes: no scene for frame " + missing.front() + " (and " +
                std::to_string(missing.size() - 1) +
                " more): give its folder a frames.csv with a scene or nyu_index column");
  }
  plan.fold_of_sample = plan.rule == "scenes" ? sceneFolds(plan.scene_of_sample, f.folds)
                                              : blockFolds(samples.size(), f.folds);
  return plan;
}

// How NYU frames' scenes are formed, for the reports.
std::string nyuSceneRule(const EvalFlags& f) {
  return f.nyu_split.empty() ? "NYU index runs with gap " + std::to_string(f.scene_gap)
                             : "runs of NYU's train/test split (" + f.nyu_split + ")";
}

// The training-frame counts of --curve-sizes ("all" = 0).
std::vector<int> curveSizes(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item == "all") {
      out.push_back(0);
      continue;
    }
    const auto n = parseInteger(item);
    if (!n || *n < 1 || *n > 1000000) {
      throw Error("--curve-sizes: '" + item + "' is neither 'all' nor an integer >= 1");
    }
    out.push_back(static_cast<int>(*n));
  }
  if (out.empty()) throw Error("--curve-sizes: empty");
  return out;
}

// Table IoU of a confusion matrix: table pixels right over truth or prediction table.
double tableIoU(const ConfusionMatrix& m) {
  const int t = static_cast<int>(Label::Table);
  const double hit = static_cast<double>(m.count(t, t));
  double predicted = 0.0;
  for (int c = 0; c < kNumLabels; ++c) predicted += static_cast<double>(m.count(c, t));
  const double denominator = static_cast<double>(m.rowTotal(t)) + predicted - hit;
  return denominator > 0 ? hit / denominator : std::nan("");
}

// --learning-curve: the CV repeated for every size and seed; one CSV row each.
void runLearningCurve(const EvalFlags& f, const LabeledFrames& test_frames,
                      const std::vector<FrameSample>& samples,
                      const std::vector<FrameSample>& test_samples,
                      const std::vector<FrameSample>& extra_training, const FoldPlan& plan,
                      const Segmenter& segmenter, const OfflineConfig& offline,
                      const std::vector<RegionFeatures>& regions) {
  const std::filesystem::path dir = f.curve_dir;
  std::filesystem::create_directories(dir);
  std::vector<LearningCurvePoint> points;
  for (int size : curveSizes(f.curve_sizes)) {
    for (int seed = 0; seed < f.curve_seeds; ++seed) {
      const auto start = std::chrono::steady_clock::now();
      SegmenterConfig config = segmenter.config();
      config.forest.seed += 1000u * static_cast<std::uint64_t>(seed);
      const TrainSubset subset{size, static_cast<std::uint64_t>(seed)};
      Evaluation eval = crossValidate(samples, test_samples, extra_training, plan, config,
                                      offline.training, regions, true, subset);
      EvalReport tables;
      measureTables(test_frames, test_samples, eval, segmenter, offline.table_metrics, nullptr,
                    tables, nullptr);
      LearningCurvePoint p;
      p.requested = size;
      p.seed = seed;
      p.forest_seed = config.forest.seed;
      double frames = 0;
      for (const auto& fold : eval.folds) frames += static_cast<double>(fold.train.size());
      p.train_frames = eval.folds.empty() ? 0.0 : frames / static_cast<double>(eval.folds.size());
      p.class_average = eval.mrf.classAverageAccuracy();
      p.global = eval.mrf.globalAccuracy();
      p.table_accuracy = eval.mrf.perClassAccuracy()[static_cast<int>(Label::Table)];
      p.table_iou = tableIoU(eval.mrf);
      p.instance_precision = tables.tables.precision();
      p.instance_recall = tables.tables.recall();
      p.searchable_precision = tables.searchable.precision();
      p.searchable_recall = tables.searchable.recall();
      p.false_table_frame_share = tables.searchable.falseTableFrameShare();
      p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr,
                   "learning curve: %s frames (%.1f per fold), seed %d: class avg %.1f, global "
                   "%.1f, table %.1f, searchable P/R %.1f/%.1f (%.0f s)\n",
                   size ? std::to_string(size).c_str() : "all", p.train_frames, seed,
                   100 * p.class_average, 100 * p.global, 100 * p.table_accuracy,
                   100 * p.searchable_precision, 100 * p.searchable_recall, p.seconds);
      points.push_back(p);
    }
  }
  const std::string protocol = describeFolds(plan, nyuSceneRule(f), {});
  writeLearningCurve(dir, points, protocol);
  std::cout << formatLearningCurveTrends(points) << "learning curve in " << dir.string() << "\n";
}

// The semi-supervised rounds side by side (forest+MRF), with what each
// fold's rounds added and how the unlabelled frames got their ground.
std::string formatPseudoRounds(const EvalReport& r, const Evaluation& eval) {
  std::ostringstream out;
  out << "\nsemi-supervised rounds (forest+MRF; round 0 = labelled frames only, same folds)\n";
  for (const auto& [frame, method] : r.unlabelled_ground_methods)
    out << "  unlabelled " << frame << " ground " << method << "\n";
  for (const auto& fold : eval.folds) {
    out << "  fold " << fold.fold << ":\n";
    std::istringstream lines(formatPseudoLabelReport(fold.pseudo));
    for (std::string line; std::getline(lines, line);) out << "    " << line << "\n";
  }
  out << "  round  class avg  global  table  chair  cabinet  search P  search R  false-table "
         "frames  inst P  inst R\n";
  for (const auto& p : r.pseudo_rounds) {
    const auto acc = p.mrf.perClassAccuracy();
    char line[256];
    std::snprintf(line, sizeof line,
                  "  %5d  %9.1f  %6.1f  %5.1f  %5.1f  %7.1f  %8.1f  %8.1f  %11d/%-6d  %6.1f  "
                  "%6.1f\n",
                  p.round, 100 * p.mrf.classAverageAccuracy(), 100 * p.mrf.globalAccuracy(),
                  100 * acc[static_cast<int>(Label::Table)],
                  100 * acc[static_cast<int>(Label::Chair)],
                  100 * acc[static_cast<int>(Label::Cabinet)], 100 * p.searchable.precision(),
                  100 * p.searchable.recall(), p.searchable.framesWithFalseTable(),
                  p.searchable.frames(), 100 * p.tables.precision(), 100 * p.tables.recall());
    out << line;
  }
  return out.str();
}

// Keeps the frames that both the clean and the raw-like extraction could use
// (a raw-like copy may lose its ground plane), in the same order, so that
// test_samples[i] is the copy of samples[i]; a frame left out is listed as
// dropped in the report.
void pairDegradedSamples(std::vector<FrameSample>& samples, std::vector<FrameSample>& degraded,
                         ExtractionReport& report) {
  std::map<std::size_t, std::size_t> degraded_of;
  for (std::size_t i = 0; i < degraded.size(); ++i) degraded_of[degraded[i].source_index] = i;
  std::vector<FrameSample> kept, kept_degraded;
  for (FrameSample& s : samples) {
    const auto it = degraded_of.find(s.source_index);
    if (it == degraded_of.end()) {
      report.dropped.push_back(s.name + ": no ground plane found on its raw-like copy");
      --report.frames_used;
      continue;
    }
    kept_degraded.push_back(std::move(degraded[it->second]));
    kept.push_back(std::move(s));
  }
  samples = std::move(kept);
  degraded = std::move(kept_degraded);
}

// --out: the confusion matrices, the sweeps and the overlays as pictures.
void writePictures(const std::string& out_dir, const EvalReport& report,
                   const LabeledFrames& test_frames, const std::vector<FrameSample>& test_samples,
                   const Evaluation& eval) {
  const std::filesystem::path dir = out_dir;
  std::filesystem::create_directories(dir);
  writeConfusionSvg((dir / "confusion_forest.svg").string(), report.forest,
                    "Forest only: row-normalised confusion (%)");
  writeConfusionSvg((dir / "confusion_mrf.svg").string(), report.mrf,
                    "Forest + MRF: row-normalised confusion (%)");
  if (!report.sweep_trees.empty()) {
    writeSweepSvg((dir / "sweep_trees.svg").string(), report.sweep_trees, true);
    writeSweepSvg((dir / "sweep_depth.svg").string(), report.sweep_depth, false);
  }
  writeOverlays(test_frames, test_samples, eval, dir / "overlays");
  std::cout << "pictures in " << dir.string() << "\n";
}

// What findmug-eval evaluates and trains on, with what the extraction reported.
struct EvalSamples {
  std::vector<FrameSample> samples;         // the labelled frames, for training
  LabeledFrames test_frames;                // the frames evaluated: the same, or raw-like
  std::vector<FrameSample> test_samples;    // copies of them (--degrade)
  std::vector<FrameSample> extra_training;  // --train-extra
  std::vector<FrameSample> unlabelled;      // --unlabelled
  ExtractionReport extraction, unlabelled_report;
};

// The features of every input frame (and of the raw-like copies, the extra training sets and
// the unlabelled frames the flags ask for), with the checks that refuse what cannot run.
EvalSamples extractEvalSamples(const EvalFlags& f, const Config& config,
                               const DatasetOptions& options, const LabeledInputs& input,
                               const Segmenter& segmenter) {
  EvalSamples out;
  ProgressBar bar("features");
  ExtractionReport& extraction = out.extraction;
  std::vector<FrameSample>& samples = out.samples;
  samples = extractTrainingSamples(input.frames(), segmenter, config.offline, extraction,
                                   [&](int done, int total) { bar.update(done, total); });
  bar.finish();
  // The frames evaluated: the same, or raw-like copies (--degrade) of them.
  out.test_frames = f.degrade
                        ? degradedFrames(input.frames(), config.offline.degrade, f.degrade_seed)
                        : input.frames();
  const LabeledFrames& test_frames = out.test_frames;
  std::vector<FrameSample>& test_samples = out.test_samples;
  if (f.degrade) {
    ProgressBar degraded_bar("features (raw-like)");
    ExtractionReport degraded_report;
    // extractSamples: the training-only views are not evaluated.
    test_samples = extractSamples(test_frames, segmenter, degraded_report,
                                  [&](int done, int total) { degraded_bar.update(done, total); });
    degraded_bar.finish();
    pairDegradedSamples(samples, test_samples, extraction);
  } else {
    test_samples = samples;
  }
  if (f.score_labelled_only) {
    for (FrameSample& s : test_samples) {
      for (std::size_t p = 0; p < s.ground_truth.size(); ++p)
        if (s.pixel_segment[p] < 0) s.ground_truth[p] = kVoidLabel;
    }
  }
  if (samples.empty()) throw Error(input.frames().description + ": no frame could be used");
  std::vector<FrameSample>& extra_training = out.extra_training;
  for (const auto& dir : f.train_extra) {
    if (!f.model.empty())
      throw Error("--train-extra trains forests; it cannot be used with --model");
    DatasetOptions extra_options = options;
    extra_options.nyu_rotations_file.reset();  // extra sets are not NYU-indexed
    const auto extra_input = LabeledInput::folder(dir, extra_options);
    ProgressBar extra_bar("features " + dir);
    ExtractionReport extra_report;
    auto part =
        extractTrainingSamples(extra_input->frames(), segmenter, config.offline, extra_report,
                               [&](int done, int total) { extra_bar.update(done, total); });
    extra_bar.finish();
    for (auto& s : part) extra_training.push_back(std::move(s));
  }
  if (!!f.model.empty() && static_cast<int>(samples.size()) < f.folds) {
    throw Error("only " + std::to_string(samples.size()) + " usable frames for " +
                std::to_string(f.folds) + " folds");
  }
  ExtractionReport& unlabelled_report = out.unlabelled_report;
  std::vector<FrameSample>& unlabelled = out.unlabelled;
  if (!f.unlabelled.empty()) {
    if (!f.model.empty())
      throw Error("--unlabelled trains forests (training.pseudo_rounds); not with --model");
    if (config.offline.training.pseudo_rounds == 0)
      std::cerr << "findmug-eval: --unlabelled without training.pseudo_rounds > 0 does nothing\n";
    unlabelled =
        extractUnlabelled(f.unlabelled, f.dataset, config.segmenter, input, unlabelled_report);
    if (unlabelled.empty())
      throw Error("--unlabelled: no frame could be used (no ground plane found in any)");
  }
  return out;
}

// The tables found on the evaluated frames against the true ones (and --table-report,
// --table-evidence); then the +MRF confusion and the table pixels by NYU-40 class, which
// follow the soft tops' relabelling there.
void measureEvaluatedTables(const EvalFlags& f, const Config& config,
                            const LabeledFrames& test_frames,
                            const std::vector<FrameSample>& test_samples,
                            const Segmenter& segmenter, Evaluation& eval, EvalReport& report) {
  std::optional<synth::SequenceGroundTruth> synth_truth;
  if (f.dataset.data.size() == 1 && f.dataset.mats.empty()) {
    const auto truth_path = std::filesystem::path(f.dataset.data.front()) / "ground_truth.yaml";
    if (std::filesystem::exists(truth_path))
      synth_truth = synth::readGroundTruth(truth_path.string());
  }
  {
    std::ofstream diagnosis;
    if (!f.table_report.empty()) {
      diagnosis.open(f.table_report);
      if (!diagnosis) throw Error(f.table_report + ": cannot write the table report");
    }
    std::ofstream evidence;
    if (!f.table_evidence.empty()) {
      evidence.open(f.table_evidence);
      if (!evidence) throw Error(f.table_evidence + ": cannot write the table evidence");
      writeTableEvidenceHeader(evidence);
    }
    measureTables(test_frames, test_samples, eval, segmenter, config.offline.table_metrics,
                  synth_truth ? &*synth_truth : nullptr, report,
                  f.table_report.empty() ? nullptr : &diagnosis,
                  {f.table_evidence.empty() ? nullptr : &evidence, &f.dataset.data});
    // After measureTables, which labels the soft tops Unknown as the pipeline does.
    report.mrf = eval.mrf;
    countTableByNyu40(f.dataset.data, test_samples, eval.mrf_pixels, report.table_by_nyu40);
    if (diagnosis.is_open()) {
      diagnosis << "\nsummary over all frames\n" << formatDiagnosisCounts(report.diagnosis);
    }
  }
}

// The text report on stdout, and the JSON report and pictures the flags ask for.
void writeReports(const EvalFlags& f, const EvalReport& report, const Evaluation& eval,
                  const LabeledFrames& test_frames, const std::vector<FrameSample>& test_samples) {
  std::cout << formatTable(report);
  if (!report.pseudo_rounds.empty()) std::cout << formatPseudoRounds(report, eval);
  if (!f.json.empty()) {
    std::ofstream out(f.json);
    if (!out) throw Error(f.json + ": cannot write JSON report");
    out << formatJson(report);
  }
  if (!f.out.empty()) writePictures(f.out, report, test_frames, test_samples, eval);
}

int run(int argc, char** argv) {
  EvalFlags f;
  const auto app = makeEvalApp(f);
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  if (f.config.help_settings) return (std::cout << cli::coreSettingsHelp(), 0);
  if (f.dataset.data.empty() && f.dataset.mats.empty()) {
    std::cerr << "findmug-eval: give --data DIR or --mat FILE (repeatable; see --help)\n";
    return 2;
  }
  Config config = cli::configFrom(f.config);
  // Loaded first: a bad file is refused before minutes of feature extraction.
  std::optional<RandomForest> model;
  if (!f.model.empty()) model = loadModelWithItsSettings(f.model, config);
  if (model && (f.train_frames > 0 || !f.curve_dir.empty()))
    throw Error("--train-frames and --learning-curve train forests; not with --model");
  const DatasetOptions options = datasetOptions(f.dataset, config);
  const auto input = LabeledInputs::open(f.dataset, options);
  const Segmenter segmenter(config.segmenter, nullptr);

  const auto start = std::chrono::steady_clock::now();
  EvalSamples input_samples = extractEvalSamples(f, config, options, *input, segmenter);
  std::vector<FrameSample>& samples = input_samples.samples;
  const LabeledFrames& test_frames = input_samples.test_frames;
  const std::vector<FrameSample>& test_samples = input_samples.test_samples;
  const std::vector<FrameSample>& extra_training = input_samples.extra_training;
  const std::vector<FrameSample>& unlabelled = input_samples.unlabelled;
  const ExtractionReport& extraction = input_samples.extraction;
  const ExtractionReport& unlabelled_report = input_samples.unlabelled_report;
  // Folds only for cross-validation: a --model run reads no frames.csv.
  const FoldPlan plan = f.model.empty() ? planFolds(f, *input, samples) : FoldPlan{};
  const TrainSubset subset{f.train_frames, f.subset_seed};

  EvalReport report;
  report.data = test_frames.description;
  for (const auto& dir : f.train_extra) report.train_extra.push_back(dir);
  report.frames_total = extraction.frames_total;
  report.frames_used = extraction.frames_used;
  report.dropped = extraction.dropped;
  report.ground_methods = extraction.ground_methods;
  report.config_yaml = dumpConfig(config);

  const std::vector<RegionFeatures> regions = sampleRegions(test_samples, segmenter.config());
  Evaluation eval;
  if (model) {
    const RandomForest& forest = *model;
    report.protocol = "model " + f.model + " (id " + forest.id() + ") on all frames";
    eval.mrf_pixels.resize(samples.size());
    eval.probabilities.resize(samples.size());
    eval.mrf_results.resize(samples.size());
    std::vector<std::size_t> all(samples.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    labelFrames(forest, config.segmenter, test_samples, all, regions, eval, true);
  } else {
    report.protocol = describeFolds(plan, nyuSceneRule(f), subset);
    report.fold_rule = plan.rule;
    report.scene_rule = nyuSceneRule(f);
    std::vector<Evaluation> per_round;
    eval = crossValidate(samples, test_samples, extra_training, plan, config.segmenter,
                         config.offline.training, regions, true, subset, unlabelled,
                         unlabelled.empty() ? nullptr : &per_round);
    report.folds = foldRecords(eval, plan, samples);
    report.unlabelled_ground_methods = unlabelled_report.ground_methods;
    for (const auto& d : unlabelled_report.dropped) report.dropped.push_back("unlabelled " + d);
    for (std::size_t r = 0; r < per_round.size(); ++r) {
      EvalReport round_tables;
      measureTables(test_frames, test_samples, per_round[r], segmenter,
                    config.offline.table_metrics, nullptr, round_tables, nullptr);
      report.pseudo_rounds.push_back(
          {static_cast<int>(r), per_round[r].mrf, round_tables.searchable, round_tables.tables});
    }
  }
  for (const FrameSample& s : test_samples)
    report.oracle.add(s.ground_truth, pixelLabels(s, s.segment_labels));
  report.forest = eval.forest;
  measureEvaluatedTables(f, config, test_frames, test_samples, segmenter, eval, report);

  if (f.sweep) {
    if (!f.model.empty()) throw Error("--sweep retrains forests; it cannot be used with --model");
    runSweeps(samples, test_samples, extra_training, plan, config, regions, subset, report);
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!f.curve_dir.empty()) {
    runLearningCurve(f, test_frames, samples, test_samples, extra_training, plan, segmenter,
                     config.offline, regions);
  }

  writeReports(f, report, eval, test_frames, test_samples);
  return 0;
}

}  // namespace
}  // namespace findmug::tools

int main(int argc, char** argv) {
  try {
    return findmug::tools::run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "findmug-eval: error: " << e.what() << "\n";
    return 1;
  }
}
