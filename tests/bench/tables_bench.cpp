// Benchmark of the table stage (detectTables: clustering, geometry, search
// positions, reachability) on labelled frames, one benchmark per frame:
//   tables/nyu/NNNN      NYU Depth V2 frames with ground-truth labels and the
//                        ground plane fitted to the floor labels (real clutter)
//   tables/synth/SEED_F  rendered apartment frames (Kinect noise model)
//   tables/close_table   the worst case: a table filling most of the view
// The target is <= 20 ms per frame, median over the frames. Each frame runs
// with tables.point_stride 1 (the default, every table point: .../stride1)
// and 2 (.../stride2), side by side. Inputs are prepared once outside the
// timed loop. Run e.g.
//   tables_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// With FINDMUG_TABLES_DUMP=FILE set, every field of every input's detection
// at both strides (floats exact, in hex) is written to FILE before timing: running the same
// binary against two builds of the core (LD_LIBRARY_PATH) and diffing the
// files shows whether a change to the table stage changed its output.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/synth/synth.hpp"
#include "findmug/tables/tables.hpp"
#include "test_data.hpp"

namespace {

using namespace findmug;

struct Input {
  std::string name;
  OrganizedCloud cloud_ground;
  LabelImage labels;
};

std::vector<Input> nyuInputs() {
  std::vector<Input> out;
  const auto dir = test::dataPath("nyuv2_labeled");
  if (dir.empty()) return out;
  const DatasetFolder dataset(dir.string());
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    const LabeledFrame frame = dataset.load(i);
    const OrganizedCloud cloud = frameToCloud(frame.frame);
    const auto ground = fitGroundToLabels(cloud, frame.labels, GroundConfig{});
    if (!ground) continue;  // the paper drops frames without enough floor too
    Input in;
    in.name = "tables/nyu/" + frame.name;
    in.cloud_ground = transformCloud(cloud, ground->camera_to_ground);
    in.labels.width = cloud.width;
    in.labels.height = cloud.height;
    in.labels.labels = frame.labels;
    in.labels.confidence.assign(frame.labels.size(), 0.8f);
    out.push_back(std::move(in));
  }
  return out;
}

Input renderInput(const synth::SynthScene& scene, const synth::CameraPose& pose, std::uint64_t seed,
                  const std::string& name) {
  const auto rendered = synth::render(scene, pose, synth::RenderOptions{}, seed);
  const RgbdFrame& frame = rendered.labeled.frame;
  const GroundPlane ground = groundFromExtrinsics(frame.extrinsics.value());
  Input in;
  in.name = name;
  in.cloud_ground = transformCloud(frameToCloud(frame), ground.camera_to_ground);
  in.labels.width = frame.width;
  in.labels.height = frame.height;
  in.labels.labels = rendered.labeled.labels;
  in.labels.confidence.assign(in.labels.labels.size(), 0.8f);
  return in;
}

std::vector<Input> synthInputs() {
  std::vector<Input> out;
  for (std::uint64_t seed : {1u, 3u}) {
    const synth::SynthScene scene = synth::makeApartment(seed);
    const auto path = synth::cameraPath(scene, 200, 10.0);
    for (std::size_t f = 0; f < path.size(); f += 40) {
      out.push_back(renderInput(scene, path[f], seed * 100 + f,
                                "tables/synth/" + std::to_string(seed) + "_" + std::to_string(f)));
    }
  }
  // A 1.6 x 0.9 m table right in front of the camera, covering most pixels.
  synth::SynthScene scene = synth::makeEmptyRoom({6.0, 5.0, 2.6});
  synth::Primitive top;
  top.center = Eigen::Vector3d(3.0, 2.5, 0.735);
  top.half_extent = Eigen::Vector3d(0.8, 0.45, 0.015);
  synth::addObject(scene, "table", Label::Table, {top});
  synth::CameraPose pose;
  pose.xy = {1.9, 2.5};
  pose.yaw = 0.0;
  pose.pitch_rad = 0.9;
  out.push_back(renderInput(scene, pose, 1, "tables/close_table"));
  return out;
}

TableConfig configWithStride(int stride) {
  TableConfig config;
  config.point_stride = stride;
  return config;
}

void runTables(benchmark::State& state, const Input* input, int stride) {
  const TableConfig config = configWithStride(stride);
  std::size_t tables = 0, positions = 0;
  for (auto _ : state) {
    TableDetection d = detectTables(input->cloud_ground, input->labels, config);
    tables = d.tables.size();
    positions = 0;
    for (const auto& t : d.tables) positions += t.search_positions.size();
    benchmark::DoNotOptimize(d);
  }
  int table_points = 0;
  for (std::uint8_t l : input->labels.labels)
    table_points += l == static_cast<std::uint8_t>(Label::Table);
  state.counters["tables"] = static_cast<double>(tables);
  state.counters["positions"] = static_cast<double>(positions);
  state.counters["table_px"] = table_points;
}

// Inputs live for the whole run; benchmarks keep pointers to them.
std::vector<Input>& inputs() {
  static std::vector<Input> all = [] {
    std::vector<Input> v = nyuInputs();
    for (auto& s : synthInputs()) v.push_back(std::move(s));
    return v;
  }();
  return all;
}

void dumpDetections(const char* path) {
  std::FILE* out = std::fopen(path, "w");
  if (!out) {
    std::fprintf(stderr, "tables_bench: cannot write %s\n", path);
    std::exit(1);
  }
  const auto v2 = [&](const char* name, const Eigen::Vector2f& v) {
    std::fprintf(out, " %s=%a,%a", name, v.x(), v.y());
  };
  for (const Input& in : inputs()) {
    for (int stride : {1, 2}) {
      const TableDetection d = detectTables(in.cloud_ground, in.labels, configWithStride(stride));
      std::fprintf(out,
                   "%s/stride%d points=%d nonfinite=%d implausible=%d rejected=%d unsampled=%d "
                   "tables=%zu\n",
                   in.name.c_str(), stride, d.table_points, d.nonfinite_points,
                   d.implausible_points, d.clusters_rejected, d.unsampled_points, d.tables.size());
      for (const auto& line : d.diagnostics) std::fprintf(out, "  diag %s\n", line.c_str());
      for (const auto& t : d.tables) {
        std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a of the pixel list
        for (int px : t.pixels) h = (h ^ static_cast<std::uint32_t>(px)) * 0x100000001b3ULL;
        std::fprintf(out, "  table id=%d n=%d top=%a conf=%a c=%a,%a,%a pixels=%zu/%016llx", t.id,
                     t.point_count, t.top_height, t.mean_confidence, t.centroid.x(), t.centroid.y(),
                     t.centroid.z(), t.pixels.size(), static_cast<unsigned long long>(h));
        v2("major", t.major_axis);
        v2("minor", t.minor_axis);
        v2("ext", t.extents);
        v2("center", t.center);
        std::fprintf(out, "\n   hull");
        for (const auto& q : t.hull) std::fprintf(out, " %a,%a", q.x(), q.y());
        std::fprintf(out, "\n");
        for (const auto& p : t.search_positions) {
          std::fprintf(out, "   pos side=%d along=%a yaw=%a reachable=%d", p.side, p.along_m, p.yaw,
                       p.reachable ? 1 : 0);
          v2("xy", p.xy);
          std::fprintf(out, " reason='%s'\n", p.reason.c_str());
        }
      }
    }
  }
  std::fclose(out);
}

const bool registered = [] {
  if (const char* dump = std::getenv("FINDMUG_TABLES_DUMP")) dumpDetections(dump);
  for (const Input& in : inputs()) {
    for (int stride : {1, 2}) {
      benchmark::RegisterBenchmark((in.name + "/stride" + std::to_string(stride)).c_str(),
                                   runTables, &in, stride)
          ->Unit(benchmark::kMillisecond);
    }
  }
  return true;
}();

}  // namespace
