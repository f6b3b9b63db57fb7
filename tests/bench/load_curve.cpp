// load_curve — how the cost of one frame grows (issue 13), one thread, the
// organized oversegmenter, ground estimated from the frame:
//   1. time per frame at 640x480 and at 320x240 (QVGA: every second pixel
//      of every second row, intrinsics halved);
//   2. time per frame and segment count against oversegmentation.seed_resolution_m;
//   3. table-stage time against the number of pixels labelled table;
//   4. heap allocations per frame in Segmenter::process (steady state:
//      global operator new calls and bytes, counted after a warm-up pass).
//
//   load_curve [--data DIR] [--repeat N]
//
// The forest is trained in-process on the data set (as stage_times does), so
// the curve does not depend on a model trained with other settings.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "counting_new.hpp"  // this program's operator new counts allocations
#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "test_data.hpp"

namespace {

using namespace findmug;

using bench::median;

RgbdFrame halve(const RgbdFrame& in) {
  RgbdFrame out = in;
  out.width = in.width / 2;
  out.height = in.height / 2;
  out.depth_mm.assign(static_cast<std::size_t>(out.width) * out.height, 0);
  out.rgb.assign(out.depth_mm.size(), Rgb8{});
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const std::size_t src = static_cast<std::size_t>(2 * y) * in.width + 2 * x;
      const std::size_t dst = static_cast<std::size_t>(y) * out.width + x;
      out.depth_mm[dst] = in.depth_mm[src];
      out.rgb[dst] = in.rgb[src];
    }
  }
  out.intrinsics.fx = in.intrinsics.fx / 2;
  out.intrinsics.fy = in.intrinsics.fy / 2;
  out.intrinsics.cx = (in.intrinsics.cx + 0.5) / 2 - 0.5;
  out.intrinsics.cy = (in.intrinsics.cy + 0.5) / 2 - 0.5;
  return out;
}

int run(int argc, char** argv) {
  std::string data = (test::dataRoot() / "nyuv2_labeled").string();
  int repeat = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--data"))
      data = argv[i + 1];
    else if (!std::strcmp(argv[i], "--repeat"))
      repeat = bench::positiveCount("--repeat", argv[i + 1]);
    else
      throw Error(std::string("unknown flag ") + argv[i]);
  }
  const DatasetFolder dataset(data);
  std::vector<LabeledFrame> frames;
  for (std::size_t i = 0; i < dataset.size(); ++i) frames.push_back(dataset.load(i));

  SegmenterConfig base;
  base.ground.source = GroundSource::Estimated;
  base.oversegmentation.kind = OversegmenterKind::Organized;
  base.forest.num_threads = 1;
  SegmenterConfig train_config = base;
  train_config.ground.source = GroundSource::FloorLabels;
  ExtractionReport report;
  const auto samples = extractSamples(dataset, Segmenter(train_config, nullptr), report);
  std::vector<std::size_t> all(samples.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  const auto forest = std::make_shared<const RandomForest>(
      RandomForest::train(makeTrainingSet(samples, all), train_config.forest));

  std::printf(
      "load_curve: %zu frames of %s, %d repetitions, one thread, medians over frames "
      "with a ground plane\n\n",
      frames.size(), data.c_str(), repeat);

  // 1. Resolution.
  std::printf("| input | total ms (median) | p90 ms | segments (median) | frames timed |\n");
  std::printf("|---|---:|---:|---:|---:|\n");
  for (const bool qvga : {false, true}) {
    const Segmenter segmenter(base, forest);
    std::vector<double> total, segments;
    for (int r = 0; r < repeat; ++r) {
      for (const auto& f : frames) {
        const RgbdFrame frame = qvga ? halve(f.frame) : f.frame;
        const LabelledFrame out = segmenter.process(frame);
        if (!out.segmented.prepared.ground) continue;
        total.push_back(out.timings.total());
        segments.push_back(static_cast<double>(out.segmented.segmentation.segments.size()));
      }
    }
    std::vector<double> sorted = total;
    std::sort(sorted.begin(), sorted.end());
    const double p90 = sorted.empty() ? 0 : sorted[sorted.size() * 9 / 10];
    std::printf("| %s | %.1f | %.1f | %.0f | %zu |\n", qvga ? "320x240" : "640x480", median(total),
                p90, median(segments), total.size());
  }

  // 2. Seed resolution (segment count).
  std::printf(
      "\n| oversegmentation.seed_resolution_m | segments (median) | total ms | "
      "oversegmentation ms | "
      "features ms | MRF ms |\n|---:|---:|---:|---:|---:|---:|\n");
  for (const float seed : {0.05f, 0.075f, 0.1f, 0.15f, 0.2f}) {
    SegmenterConfig config = base;
    config.oversegmentation.seed_resolution_m = seed;
    const Segmenter segmenter(config, forest);
    std::vector<double> total, oversegmentation, features, mrf, segments;
    for (int r = 0; r < repeat; ++r) {
      for (const auto& f : frames) {
        const LabelledFrame out = segmenter.process(f.frame);
        if (!out.segmented.prepared.ground) continue;
        total.push_back(out.timings.total());
        oversegmentation.push_back(out.timings.oversegmentation_ms);
        features.push_back(out.timings.features_ms);
        mrf.push_back(out.timings.mrf_ms);
        segments.push_back(static_cast<double>(out.segmented.segmentation.segments.size()));
      }
    }
    std::printf("| %.3f | %.0f | %.1f | %.1f | %.1f | %.1f |\n", seed, median(segments),
                median(total), median(oversegmentation), median(features), median(mrf));
  }

  // 3. Table points: table-stage time per frame, grouped by pixels labelled table.
  {
    const Segmenter segmenter(base, forest);
    struct Bin {
      std::size_t lo, hi;
      std::vector<double> ms;
    };
    std::vector<Bin> bins = {{0, 1, {}},         {1, 10000, {}},      {10000, 30000, {}},
                             {30000, 60000, {}}, {60000, 120000, {}}, {120000, 400000, {}}};
    for (int r = 0; r < repeat; ++r) {
      for (const auto& f : frames) {
        const LabelledFrame out = segmenter.process(f.frame);
        if (!out.segmented.prepared.ground) continue;
        const auto n =
            static_cast<std::size_t>(std::count(out.labels.labels.begin(), out.labels.labels.end(),
                                                static_cast<std::uint8_t>(Label::Table)));
        for (auto& b : bins) {
          if (n >= b.lo && n < b.hi) b.ms.push_back(out.timings.tables_ms);
        }
      }
    }
    std::printf(
        "\n| pixels labelled table | frames | tables ms (median) | max ms |\n"
        "|---|---:|---:|---:|\n");
    for (const auto& b : bins) {
      if (b.ms.empty()) continue;
      std::printf("| %zu–%zu | %zu | %.1f | %.1f |\n", b.lo, b.hi - 1, b.ms.size(), median(b.ms),
                  *std::max_element(b.ms.begin(), b.ms.end()));
    }
  }

  // 4. Allocations per frame, steady state (a warm-up pass first).
  {
    const Segmenter segmenter(base, forest);
    for (const auto& f : frames) segmenter.process(f.frame);
    std::vector<double> news, mbytes;
    for (const auto& f : frames) {
      const RgbdFrame frame = f.frame;  // the copy is the caller's, not counted
      const std::uint64_t n0 = bench::g_news.load(), b0 = bench::g_bytes.load();
      { const LabelledFrame out = segmenter.process(frame); }
      news.push_back(static_cast<double>(bench::g_news.load() - n0));
      mbytes.push_back(static_cast<double>(bench::g_bytes.load() - b0) / 1048576.0);
    }
    std::printf(
        "\nHeap allocations per frame in Segmenter::process (steady state, 640x480): "
        "median %.0f operator-new calls, %.1f MB; max %.0f calls\n",
        median(news), median(mbytes), *std::max_element(news.begin(), news.end()));
  }
  return 0;
}

}  // namespace

// Its own main, not bench::benchMain: GCC 12 then takes the counting operator delete
// above for a mismatched one inside run() (-Wmismatched-new-delete, a false positive).
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "load_curve: error: %s\n", e.what());
    return 1;
  }
}
