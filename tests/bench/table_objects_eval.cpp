// table_objects_eval — how well the table-top object stage (table_objects.hpp)
// finds the objects standing on tables, and what it costs, on ground-truth
// labels: rendered rooms (findmug_synth; every mug, box and book known) and the
// 46 labelled NYU Depth V2 frames ($FINDMUG_DATA/nyuv2_labeled and
// nyuv2_labeled_extra, gravity from camera_rotations_NYU.txt).
//
// Per data set: recall of the true objects standing on a detected table
// (rendered: mugs/boxes/books with >= 100 points, off the image border, most
// points above a detected top; NYU: 4-connected components of Object pixels
// with >= 100 points above a top and a footprint within max_extent_m), found
// when one candidate holds half their points above the top or more; precision
// (candidates whose pixels are mostly Object); false candidates per frame; the
// median centroid error (rendered: footprint centre to the true object's centre
// on the floor; NYU: candidate centroid to the instance's points' mean); and
// the stage's CPU time per frame (findTableObjects alone, this thread's clock,
// median and maximum over the frames with a table).
//
//   table_objects_eval [--seeds N] [--frames N] [--strides 1,2] [--per-frame]
// --strides: the table_objects.point_stride values measured, one after the
// other in the same run (default 1 and 2: the exact clustering and the
// shipped sampled one), so that their figures and times sit side by side.
// --per-frame lists the NYU frames with a table: points above the tops,
// candidates, CPU time.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/synth/synth.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr auto kObject = static_cast<std::uint8_t>(Label::Object);

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

float median(std::vector<float> v) {
  if (v.empty()) return 0.0f;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// The q-quantile (nearest rank).
float quantile(std::vector<float> v, double q) {
  if (v.empty()) return 0.0f;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

// The stage's settings under measurement (defaults but for --strides).
TableObjectConfig g_config;

struct Score {
  int frames = 0, frames_with_tables = 0, objects = 0, found = 0, candidates = 0,
      false_candidates = 0;
  std::vector<float> centroid_errors, cpu_ms;

  void print(const char* name) const {
    std::printf(
        "%s: %d frames (%d with a table), %d true objects on the tables, %d found "
        "(recall %.3f); %d candidates, %d mostly not object pixels (precision %.3f, "
        "%.2f false candidates per frame with a table); median centroid error %.4f m; "
        "stage CPU time per frame with a table: median %.3f ms, p95 %.3f ms, max %.3f ms\n",
        name, frames, frames_with_tables, objects, found,
        objects ? static_cast<double>(found) / objects : 0.0, candidates, false_candidates,
        candidates ? 1.0 - static_cast<double>(false_candidates) / candidates : 0.0,
        frames_with_tables ? static_cast<double>(false_candidates) / frames_with_tables : 0.0,
        median(centroid_errors), median(cpu_ms), quantile(cpu_ms, 0.95),
        cpu_ms.empty() ? 0.0f : *std::max_element(cpu_ms.begin(), cpu_ms.end()));
  }
};

// The candidates, timed (best of three runs: the stage alone, caches warm).
TableObjectDetection timedObjects(const OrganizedCloud& cloud, const LabelImage& labels,
                                  const std::vector<TableCluster>& tables, Score& score) {
  TableObjectDetection d;
  double best = 1e30;
  for (int k = 0; k < 3; ++k) {
    const double t0 = threadCpuMs();
    findTableObjectsInto(cloud, labels, tables, g_config, d);
    best = std::min(best, threadCpuMs() - t0);
  }
  score.cpu_ms.push_back(static_cast<float>(best));
  return d;
}

// Candidates mostly made of pixels that are not Object: false ones. Returns
// per pixel the candidate holding it (-1: none).
std::vector<int> countCandidates(const TableObjectDetection& d, const LabelImage& labels,
                                 Score& score) {
  std::vector<int> candidate_of(labels.labels.size(), -1);
  for (const TableObject& o : d.objects) {
    int object_pixels = 0;
    for (const int p : o.pixels) {
      candidate_of[static_cast<std::size_t>(p)] = o.id;
      object_pixels += labels.labels[static_cast<std::size_t>(p)] == kObject;
    }
    ++score.candidates;
    if (2 * object_pixels < o.point_count) ++score.false_candidates;
  }
  return candidate_of;
}

// The candidate holding half of `points` or more, or -1.
int matchingCandidate(const std::vector<int>& points, const std::vector<int>& candidate_of) {
  std::map<int, int> votes;
  for (const int p : points) {
    if (candidate_of[static_cast<std::size_t>(p)] >= 0)
      ++votes[candidate_of[static_cast<std::size_t>(p)]];
  }
  for (const auto& [id, n] : votes) {
    if (2 * n >= static_cast<int>(points.size())) return id;
  }
  return -1;
}

// Per pixel: whether its point is above a top (the stage with every cluster kept).
std::vector<std::uint8_t> aboveTops(const OrganizedCloud& cloud, const LabelImage& labels,
                                    const std::vector<TableCluster>& tables) {
  TableObjectConfig probe;
  probe.min_points = 1;
  probe.max_base_height_m = probe.max_height_m;
  probe.max_extent_m = 10.0f;
  probe.point_stride = 1;  // the truth's "above a top" does not depend on the stride measured
  std::vector<std::uint8_t> above(labels.labels.size(), 0);
  for (const TableObject& o : findTableObjects(cloud, labels, tables, probe).objects) {
    for (const int p : o.pixels) above[static_cast<std::size_t>(p)] = 1;
  }
  return above;
}

bool nearBorder(int pixel, int width, int height) {
  const int x = pixel % width, y = pixel / width;
  return x < 2 || y < 2 || x >= width - 2 || y >= height - 2;
}

void scoreRendered(const synth::SynthScene& scene, const synth::CameraPose& pose,
                   const synth::RenderedFrame& r, Score& score) {
  const OrganizedCloud cloud = frameToCloud(r.labeled.frame);
  const GroundPlane ground = groundFromExtrinsics(*r.labeled.frame.extrinsics);
  const OrganizedCloud cloud_ground = transformCloud(cloud, ground.camera_to_ground);
  LabelImage labels;
  labels.width = cloud.width;
  labels.height = cloud.height;
  labels.labels = r.labeled.labels;
  labels.confidence.assign(labels.labels.size(), 1.0f);
  for (std::size_t i = 0; i < labels.labels.size(); ++i) {
    if (!cloud.valid(i)) labels.labels[i] = kVoidLabel;
  }
  ++score.frames;
  const std::vector<TableCluster> tables = findTables(cloud_ground, labels, TableConfig{});
  if (tables.empty()) return;
  ++score.frames_with_tables;
  const TableObjectDetection d = timedObjects(cloud_ground, labels, tables, score);
  const std::vector<int> candidate_of = countCandidates(d, labels, score);
  const std::vector<std::uint8_t> above = aboveTops(cloud_ground, labels, tables);
  std::map<int, std::vector<int>> pixels_of;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (!cloud.valid(i)) continue;
    const std::string& kind = scene.objects[static_cast<std::size_t>(r.object[i])].kind;
    if (kind == "mug" || kind == "box" || kind == "book")
      pixels_of[r.object[i]].push_back(static_cast<int>(i));
  }
  for (const auto& [obj, pixels] : pixels_of) {
    if (pixels.size() < 100 || std::any_of(pixels.begin(), pixels.end(), [&](int p) {
          return nearBorder(p, cloud.width, cloud.height);
        })) {
      continue;
    }
    std::vector<int> on_top;
    for (const int p : pixels) {
      if (above[static_cast<std::size_t>(p)]) on_top.push_back(p);
    }
    if (on_top.size() < 100 || 2 * on_top.size() < pixels.size()) continue;
    ++score.objects;
    const int id = matchingCandidate(on_top, candidate_of);
    if (id < 0) continue;
    ++score.found;
    for (const synth::Primitive& part : scene.primitives) {
      if (part.object != obj) continue;
      const Eigen::Vector2d truth = (synth::worldToGround(pose) * part.center).head<2>();
      score.centroid_errors.push_back(static_cast<float>(
          (d.objects[static_cast<std::size_t>(id)].center.cast<double>() - truth).norm()));
      break;
    }
  }
}

// NYU's object instances above the tops (see the file comment).
std::vector<std::vector<int>> nyuInstances(const OrganizedCloud& cloud, const LabelImage& labels,
                                           const std::vector<std::uint8_t>& above) {
  const int w = cloud.width, h = cloud.height;
  std::vector<int> seen(cloud.points.size(), 0);
  std::vector<std::vector<int>> instances;
  for (int start = 0; start < w * h; ++start) {
    const auto s0 = static_cast<std::size_t>(start);
    if (seen[s0] || labels.labels[s0] != kObject || !cloud.valid(s0)) continue;
    std::vector<int> stack = {start}, on_top;
    seen[s0] = 1;
    Eigen::AlignedBox2f box;
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      const auto up = static_cast<std::size_t>(p);
      if (above[up]) {
        on_top.push_back(p);
        box.extend(cloud.points[up].head<2>());
      }
      const int x = p % w, y = p / w;
      const int around[4] = {x > 0 ? p - 1 : -1, x + 1 < w ? p + 1 : -1, y > 0 ? p - w : -1,
                             y + 1 < h ? p + w : -1};
      for (const int q : around) {
        if (q < 0) continue;
        const auto uq = static_cast<std::size_t>(q);
        if (seen[uq] || labels.labels[uq] != kObject || !cloud.valid(uq) ||
            (cloud.points[uq] - cloud.points[up]).norm() > 0.05f) {
          continue;
        }
        seen[uq] = 1;
        stack.push_back(q);
      }
    }
    if (on_top.size() < 100 || box.sizes().maxCoeff() > TableObjectConfig{}.max_extent_m) continue;
    std::sort(on_top.begin(), on_top.end());
    instances.push_back(std::move(on_top));
  }
  return instances;
}

void scoreNyuFolder(const std::string& dir, const std::string& rotations, bool per_frame,
                    Score& score) {
  DatasetOptions options;
  options.nyu_rotations_file = rotations;
  const DatasetFolder folder(dir, options);
  SegmenterConfig config;
  config.ground.source = GroundSource::Gravity;
  const Segmenter segmenter(config, nullptr);
  for (std::size_t i = 0; i < folder.size(); ++i) {
    LabeledFrame f = folder.load(i);
    const PreparedFrame p = segmenter.prepare(std::move(f.frame), &f.labels);
    ++score.frames;
    if (!p.ground) continue;
    LabelImage labels;
    labels.width = p.cloud_ground.width;
    labels.height = p.cloud_ground.height;
    labels.labels = f.labels;
    labels.confidence.assign(labels.labels.size(), 1.0f);
    const TableDetection tables =
        detectTables(p.cloud_ground, labels, TableConfig{}, &p.normals_ground);
    if (tables.tables.empty()) continue;
    ++score.frames_with_tables;
    const TableObjectDetection d = timedObjects(p.cloud_ground, labels, tables.tables, score);
    if (per_frame) {
      std::printf("  %s: %zu tables, %d points above the tops, %zu candidates, %.3f ms\n",
                  f.name.c_str(), tables.tables.size(), d.points_above_tops, d.objects.size(),
                  static_cast<double>(score.cpu_ms.back()));
    }
    const std::vector<int> candidate_of = countCandidates(d, labels, score);
    const auto above = aboveTops(p.cloud_ground, labels, tables.tables);
    for (const auto& instance : nyuInstances(p.cloud_ground, labels, above)) {
      ++score.objects;
      const int id = matchingCandidate(instance, candidate_of);
      if (id < 0) continue;
      ++score.found;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const int q : instance)
        mean += p.cloud_ground.points[static_cast<std::size_t>(q)].cast<double>();
      mean /= static_cast<double>(instance.size());
      score.centroid_errors.push_back(static_cast<float>(
          (d.objects[static_cast<std::size_t>(id)].centroid.cast<double>() - mean).norm()));
    }
  }
}

int run(int argc, char** argv) {
  int seeds = 8, frames = 8;
  std::vector<int> strides = {1, 2};
  bool per_frame = false;
  for (int i = 1; i < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--per-frame") {
      per_frame = true;
      --i;
    } else if (i + 1 >= argc) {
      std::fprintf(stderr, "%s needs a value\n", flag.c_str());
      return 2;
    } else if (flag == "--seeds") {
      seeds = std::atoi(argv[i + 1]);
    } else if (flag == "--frames") {
      frames = std::atoi(argv[i + 1]);
    } else if (flag == "--strides") {
      strides.clear();
      for (const char* p = argv[i + 1]; *p;) {
        char* end = nullptr;
        const long v = std::strtol(p, &end, 10);
        if (end == p || v < 1 || v > 8) {
          std::fprintf(stderr, "--strides: a comma-separated list of 1..8, not '%s'\n",
                       argv[i + 1]);
          return 2;
        }
        strides.push_back(static_cast<int>(v));
        p = *end == ',' ? end + 1 : end;
      }
    } else {
      std::fprintf(stderr,
                   "usage: table_objects_eval [--seeds N] [--frames N] [--strides 1,2] "
                   "[--per-frame]\n");
      return 2;
    }
  }
  const auto rotations = test::dataPath("nyuv2_meta/camera_rotations_NYU.txt");
  for (const int stride : strides) {
    g_config = TableObjectConfig{};
    g_config.point_stride = stride;
    std::printf("## table_objects.point_stride %d\n", stride);
    Score rendered;
    for (int seed = 1; seed <= seeds; ++seed) {
      const synth::SynthScene scene = synth::makeApartment(static_cast<std::uint64_t>(seed));
      const auto poses = synth::cameraPath(scene, frames, 1.0);
      for (std::size_t f = 0; f < poses.size(); ++f) {
        scoreRendered(scene, poses[f], synth::render(scene, poses[f], synth::RenderOptions{}, f),
                      rendered);
      }
    }
    rendered.print(("rendered (seeds 1.." + std::to_string(seeds) + ", " +
                    std::to_string(frames) + " frames each, 640x480, Kinect noise)")
                       .c_str());
    Score nyu;
    for (const char* set : {"nyuv2_labeled", "nyuv2_labeled_extra"}) {
      const auto dir = test::dataPath(set);
      if (dir.empty() || rotations.empty()) {
        std::printf("NYU: %s or the rotations missing under %s\n", set, test::dataRoot().c_str());
        continue;
      }
      scoreNyuFolder(dir.string(), rotations.string(), per_frame, nyu);
    }
    nyu.print("NYU (labelled frames, ground-truth labels, gravity ground)");
  }
  return 0;
}

}  // namespace
}  // namespace findmug

int main(int argc, char** argv) { return findmug::run(argc, argv); }
