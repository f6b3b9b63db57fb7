// Oversegmentation: PCL supervoxels (the paper's) vs the organized
// oversegmenter on the NYU Depth V2 frames in $FINDMUG_DATA/nyuv2_labeled.
//
// Each benchmark iteration segments every frame once; per frame we record wall
// and thread-CPU time, and (untimed) the segment count, boundary recall
// within 1 and 2 px and the undersegmentation error against the label8
// ground truth. Counters (means over frames unless named otherwise):
//   median_ms, median_cpu_ms  per-frame median wall / CPU time
//   segments                  mean segment count
//   count_vs_pcl              mean organized/PCL segment count ratio
//   within_10pct              share of frames whose count is within 10 % of PCL's
//   br1, br2, ue              boundary recall (1 px, 2 px), undersegmentation error
//
// Organized runs twice: with the default config (organized_seed_density
// calibrated to PCL's mean count) and with the density tuned per frame
// (untimed, before the run) so that each frame's count is within 10 % of
// PCL's: that is the like-for-like comparison.
//
//   FINDMUG_BENCH_FRAMES=N   use the first N frames only (default: all 31)
//   FINDMUG_BENCH_VERBOSE=1  print one line per frame to stderr
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "findmug/cloud/cloud.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

struct Frame {
  std::string name;
  OrganizedCloud cloud;
  NormalImage normals;
  std::vector<std::uint8_t> labels;
  int pcl_segments = 0;
  float matched_density = 0;  // organized_seed_density giving PCL's count +-10 %
};

OversegmentationConfig configFor(OversegmenterKind kind) {
  OversegmentationConfig c;
  c.kind = kind;
  return c;
}

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

bool verbose() {
  const char* v = std::getenv("FINDMUG_BENCH_VERBOSE");
  return v && *v && std::string(v) != "0";
}

// Loaded once; PCL's counts and the matched densities are computed here,
// outside any timing. Empty with `error` set when the data is missing.
struct Frames {
  std::vector<Frame> frames;
  std::string error;
};

const Frames& frames() {
  static const Frames loaded = [] {
    Frames out;
    const auto dir = test::dataPath("nyuv2_labeled");
    if (dir.empty()) {
      out.error = "NYU frames missing: " + (test::dataRoot() / "nyuv2_labeled").string();
      return out;
    }
    const DatasetFolder dataset(dir.string());
    std::size_t count = dataset.size();
    if (const char* n = std::getenv("FINDMUG_BENCH_FRAMES"); n && *n) {
      count = std::min<std::size_t>(
          count, static_cast<std::size_t>(bench::positiveCount("FINDMUG_BENCH_FRAMES", n)));
    }
    const auto pcl = makeOversegmenter(configFor(OversegmenterKind::PclSupervoxels));
    for (std::size_t i = 0; i < count; ++i) {
      const LabeledFrame lf = dataset.load(i);
      Frame f;
      f.name = lf.name;
      f.cloud = frameToCloud(lf.frame);
      f.normals = computeNormals(f.cloud, NormalConfig{});
      f.labels = lf.labels;
      f.pcl_segments = static_cast<int>(pcl->segment(f.cloud, f.normals).segments.size());
      // The organized count is proportional to the density: a few
      // proportional corrections land within 10 %.
      OversegmentationConfig c = configFor(OversegmenterKind::Organized);
      for (int attempt = 0; attempt < 8; ++attempt) {
        const int organized =
            static_cast<int>(makeOversegmenter(c)->segment(f.cloud, f.normals).segments.size());
        if (std::abs(organized - f.pcl_segments) <= 0.05 * f.pcl_segments || organized == 0) break;
        c.organized_seed_density *=
            static_cast<float>(f.pcl_segments) / static_cast<float>(organized);
      }
      f.matched_density = c.organized_seed_density;
      out.frames.push_back(std::move(f));
    }
    return out;
  }();
  return loaded;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

enum class Mode { Pcl, OrganizedDefault, OrganizedMatched };

void runOversegmentation(benchmark::State& state, Mode mode) {
  const Frames& data = frames();
  if (!data.error.empty()) {
    state.SkipWithError(data.error.c_str());
    return;
  }
  const std::vector<Frame>& fs = data.frames;
  // Oversegmenters are built before timing (one per frame when matched).
  std::vector<std::unique_ptr<Oversegmenter>> segmenters;
  for (const Frame& f : fs) {
    OversegmentationConfig c = configFor(mode == Mode::Pcl ? OversegmenterKind::PclSupervoxels
                                                           : OversegmenterKind::Organized);
    if (mode == Mode::OrganizedMatched) c.organized_seed_density = f.matched_density;
    segmenters.push_back(makeOversegmenter(c));
  }

  std::vector<double> wall_ms, cpu_ms;
  std::vector<Oversegmentation> last(fs.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < fs.size(); ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = threadCpuMs();
      last[i] = segmenters[i]->segment(fs[i].cloud, fs[i].normals);
      const double c1 = threadCpuMs();
      const auto t1 = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(last[i].pixel_segment.data());
      wall_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      cpu_ms.push_back(c1 - c0);
    }
  }

  double segments = 0, ratio = 0, within = 0, br1 = 0, br2 = 0, ue = 0;
  int br_frames = 0;
  for (std::size_t i = 0; i < fs.size(); ++i) {
    const auto q1 = evaluateOversegmentation(last[i], fs[i].labels, 1);
    const auto q2 = evaluateOversegmentation(last[i], fs[i].labels, 2);
    const double r = static_cast<double>(q2.segment_count) / std::max(fs[i].pcl_segments, 1);
    segments += q2.segment_count;
    ratio += r;
    within += std::fabs(r - 1.0) <= 0.1;
    ue += q2.undersegmentation_error;
    if (!std::isnan(q2.boundary_recall)) {  // a frame may have no labelled boundary
      br1 += q1.boundary_recall;
      br2 += q2.boundary_recall;
      ++br_frames;
    }
    if (verbose()) {
      std::fprintf(stderr, "%-18s %s segments %5d (PCL %5d) BR1 %.3f BR2 %.3f UE %.3f\n",
                   mode == Mode::Pcl                ? "pcl"
                   : mode == Mode::OrganizedDefault ? "organized"
                                                    : "organized_matched",
                   fs[i].name.c_str(), q2.segment_count, fs[i].pcl_segments, q1.boundary_recall,
                   q2.boundary_recall, q2.undersegmentation_error);
    }
  }
  const double n = static_cast<double>(fs.size());
  state.counters["frames"] = n;
  state.counters["median_ms"] = median(wall_ms);
  state.counters["median_cpu_ms"] = median(cpu_ms);
  state.counters["segments"] = segments / n;
  state.counters["count_vs_pcl"] = ratio / n;
  state.counters["within_10pct"] = within / n;
  state.counters["br1"] = br_frames ? br1 / br_frames : std::nan("");
  state.counters["br2"] = br_frames ? br2 / br_frames : std::nan("");
  state.counters["ue"] = ue / n;
}

void BM_OversegPclSupervoxels(benchmark::State& state) { runOversegmentation(state, Mode::Pcl); }
void BM_OversegOrganized(benchmark::State& state) {
  runOversegmentation(state, Mode::OrganizedDefault);
}
void BM_OversegOrganizedMatchedCount(benchmark::State& state) {
  runOversegmentation(state, Mode::OrganizedMatched);
}

// Iterations are whole passes over the frames; PCL is slow, one pass will do.
BENCHMARK(BM_OversegPclSupervoxels)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_OversegOrganized)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_OversegOrganizedMatchedCount)->Unit(benchmark::kMillisecond)->Iterations(5);

}  // namespace
}  // namespace findmug
