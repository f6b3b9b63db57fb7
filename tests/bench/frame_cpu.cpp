// frame_cpu — what one frame costs the core library on one thread, as CPU
// time (not wall time: on a shared machine wall time also counts the time
// other processes ran), per stage, and how many heap allocations it makes.
// The frames of a data set are run as a stream, in order, one pass after the
// other, through ONE Segmenter (state kept between frames, as in the daemon).
// The first pass is a warm-up; the figures are over the following passes.
//
//   frame_cpu --model MODEL [--data DIR] [--passes N] [--config YAML] [--set section.key=value]...
//             [--digest FILE] [--per-frame CSV] [--heap-keep-mb MB] [--recycle 0|1]
//
// --digest writes one line per frame of the first timed pass: the ground
// plane and a hash of the label image and of the tables' hull sizes, so two
// builds can be checked to give the same results (`diff` the files).
// --per-frame writes one CSV row per run the medians cover (pass, frame, CPU
// ms of each stage, total): which frames are the slow ones, and in which
// stage. The daemon drops frames when slow ones come in a row, which medians
// hide.
// --heap-keep-mb sets the malloc thresholds as findmugd's daemon.heap_keep_mb.
// --recycle 1 (default) hands each finished frame back with
// Segmenter::recycle, as findmugd does after publishing; 0 does not.
//
// --config comes before the --set flags it should not override; it may be findmugd's own
// file (`--config daemon/findmugd.yaml`: the shipped configuration; its daemon's sections
// are read and not used). Defaults:
// the NYU labelled frames, 3 passes after the warm-up, the library's default
// config (ground.source auto: NYU frames carry no
// extrinsics, so the floor is estimated from the frame, as in the daemon).
// Prints a Markdown table for perf-log §9.
#include <dlfcn.h>
#include <malloc.h>

#include <algorithm>
#include <array>
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
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "program_settings.hpp"
#include "findmug/tables/tables.hpp"
#include "test_data.hpp"

namespace {

using namespace findmug;

using bench::median;

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

// The segmenter's settings of a config file that may also hold other programs' sections
// (daemon/findmugd.yaml as it ships): those are checked key by key and not used.
Config sharedConfigFile(const std::string& path) {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  cli::acceptSharedFileSettings(schema);
  schema.readFile(path);
  schema.validate(path);
  return config;
}

int run(int argc, char** argv) {
  std::string data = (test::dataRoot() / "nyuv2_labeled").string();
  std::string model_path;
  int passes = 3;
  Config config;
  std::string digest_path;
  std::string per_frame_path;
  int heap_keep_mb = 0;
  bool recycle = true;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--data"))
      data = argv[i + 1];
    else if (!std::strcmp(argv[i], "--model"))
      model_path = argv[i + 1];
    else if (!std::strcmp(argv[i], "--passes"))
      passes = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--digest"))
      digest_path = argv[i + 1];
    else if (!std::strcmp(argv[i], "--per-frame"))
      per_frame_path = argv[i + 1];
    else if (!std::strcmp(argv[i], "--recycle"))
      recycle = std::atoi(argv[i + 1]) != 0;
    else if (!std::strcmp(argv[i], "--heap-keep-mb"))
      heap_keep_mb = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--config"))
      config = sharedConfigFile(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--set"))
      applyOverride(config, argv[i + 1]);
    else
      throw Error(std::string("unknown flag ") + argv[i]);
  }
  if (argc % 2 == 0) throw Error(std::string("flag ") + argv[argc - 1] + " has no value");
  if (model_path.empty()) throw Error("--model MODEL is required");
  // As findmugd's daemon.heap_keep_mb: freed frame buffers stay in the heap.
  if (heap_keep_mb > 0) {
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, heap_keep_mb << 20);
  }
  config.segmenter.forest.num_threads = 1;

  DatasetOptions options;
  options.require_labels = false;
  const DatasetFolder dataset(data, options);
  std::vector<RgbdFrame> frames;
  std::vector<std::vector<std::uint8_t>> truth;
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    LabeledFrame f = dataset.load(i);
    frames.push_back(std::move(f.frame));
    truth.push_back(std::move(f.labels));
  }
  std::size_t truth_pixels = 0, correct_pixels = 0;  // first timed pass, labelled data only
  auto forest = std::make_shared<const RandomForest>(RandomForest::load(model_path));
  const Segmenter segmenter(config.segmenter, forest);
  // The frames are one stream, as findmugd's prepare stage takes them: the floor it
  // follows (ground.reestimate_every_frames) carries over from the warm-up to every pass.
  GroundTracker ground;

  for (const auto& f : frames) {  // warm-up: caches, page faults, scratch
    LabelledFrame out = segmenter.process(f, ground);
    if (recycle) segmenter.recycle(std::move(out));
  }

  const std::pair<const char*, double StageTimings::*> stages[] = {
      {"cloud", &StageTimings::cloud_ms},       {"normals", &StageTimings::normals_ms},
      {"ground", &StageTimings::ground_ms},
      {"oversegmentation", &StageTimings::oversegmentation_ms},
      {"features", &StageTimings::features_ms}, {"regions", &StageTimings::regions_ms},
      {"forest", &StageTimings::forest_ms},     {"mrf", &StageTimings::mrf_ms},
      {"labels", &StageTimings::labels_ms},     {"tables", &StageTimings::tables_ms},
      {"objects", &StageTimings::objects_ms}};
  std::vector<std::vector<double>> cpu(std::size(stages)), wall(std::size(stages));
  std::vector<double> cpu_total, wall_total, news, megabytes;
  std::array<std::vector<double>, 3> news_split;  // prepare, oversegment, classify
  std::size_t labelled = 0, runs = 0;
  std::FILE* digest = digest_path.empty() ? nullptr : std::fopen(digest_path.c_str(), "w");
  if (!digest_path.empty() && !digest) throw Error("cannot write " + digest_path);
  std::FILE* per_frame = per_frame_path.empty() ? nullptr : std::fopen(per_frame_path.c_str(), "w");
  if (!per_frame_path.empty() && !per_frame) throw Error("cannot write " + per_frame_path);
  if (per_frame) {
    std::fprintf(per_frame, "pass,frame");
    for (const auto& stage : stages) std::fprintf(per_frame, ",%s", stage.first);
    std::fprintf(per_frame, ",total\n");
  }
  for (int pass = 0; pass < passes; ++pass) {
    for (std::size_t fi = 0; fi < frames.size(); ++fi) {
      const RgbdFrame& f = frames[fi];
      RgbdFrame frame = f;  // the copy is the caller's (the source's), not the pipeline's
      const std::uint64_t news_before = bench::g_news.load();
      const std::uint64_t bytes_before = bench::g_bytes.load();
      // process() is exactly these three calls; made one by one to count the
      // allocations of each.
      PreparedFrame prepared = segmenter.prepare(std::move(frame), ground);
      const std::uint64_t news_prepared = bench::g_news.load();
      SegmentedFrame segmented = segmenter.oversegment(std::move(prepared));
      const std::uint64_t news_segmented = bench::g_news.load();
      LabelledFrame out = segmenter.classify(std::move(segmented));
      const double calls = static_cast<double>(bench::g_news.load() - news_before);
      const std::array<double, 3> split = {
          static_cast<double>(news_prepared - news_before),
          static_cast<double>(news_segmented - news_prepared),
          static_cast<double>(bench::g_news.load() - news_segmented)};
      const double mb = static_cast<double>(bench::g_bytes.load() - bytes_before) / 1e6;
      ++runs;
      if (pass == 0 && truth[fi].size() == out.labels.labels.size()) {
        for (std::size_t p = 0; p < truth[fi].size(); ++p) {
          if (truth[fi][p] == kVoidLabel) continue;
          ++truth_pixels;
          correct_pixels += out.labels.labels[p] == truth[fi][p];
        }
      }
      if (digest && pass == 0) {
        std::uint64_t h = 1469598103934665603ull;  // FNV-1a over labels, then table hull sizes
        auto mix = [&h](std::uint64_t x) { h = (h ^ x) * 1099511628211ull; };
        for (std::uint8_t l : out.labels.labels) mix(l);
        for (const auto& t : out.tables) mix(t.hull.size());
        const auto& g = out.segmented.prepared.ground;
        std::fprintf(digest, "%s ground %s %.5f %.5f %.5f %.4f labels %016llx tables %zu\n",
                     dataset.names()[fi].c_str(), g ? "yes" : "no", g ? g->normal_camera.x() : 0.0,
                     g ? g->normal_camera.y() : 0.0, g ? g->normal_camera.z() : 0.0,
                     g ? g->offset : 0.0f, static_cast<unsigned long long>(h), out.tables.size());
      }
      // Frames without a ground plane skip most stages: time full runs only.
      if (!out.segmented.prepared.ground) {
        if (recycle) segmenter.recycle(std::move(out));
        continue;
      }
      ++labelled;
      news.push_back(calls);
      for (std::size_t k = 0; k < split.size(); ++k) news_split[k].push_back(split[k]);
      megabytes.push_back(mb);
      for (std::size_t s = 0; s < std::size(stages); ++s) {
        cpu[s].push_back(out.cpu_timings.*stages[s].second);
        wall[s].push_back(out.timings.*stages[s].second);
      }
      cpu_total.push_back(out.cpu_timings.total());
      if (per_frame) {
        std::fprintf(per_frame, "%d,%s", pass, dataset.names()[fi].c_str());
        for (const auto& stage : stages) {
          std::fprintf(per_frame, ",%.3f", out.cpu_timings.*stage.second);
        }
        std::fprintf(per_frame, ",%.3f\n", out.cpu_timings.total());
      }
      wall_total.push_back(out.timings.total());
      // As findmugd does after publishing: the buffers serve the next frame.
      if (recycle) segmenter.recycle(std::move(out));
    }
  }

  if (digest) std::fclose(digest);
  if (per_frame && std::fclose(per_frame) != 0) throw Error("cannot write " + per_frame_path);
  // Which copy of the core ran: the loader may pick the x86-64-v3 one in a
  // glibc-hwcaps folder (src/CMakeLists.txt); tests/hwcaps reads this line.
  Dl_info core{};
  if (dladdr(reinterpret_cast<const void*>(&validateTableConfig), &core) != 0 && core.dli_fname) {
    std::printf("core library: %s\n", core.dli_fname);
  }
  std::printf(
      "%zu frames x %d passes from %s, model %s, one thread; medians over the %zu of %zu runs that "
      "found a ground plane (full pipeline)\n\n",
      frames.size(), passes, data.c_str(), model_path.c_str(), labelled, runs);
  if (truth_pixels > 0) {
    std::printf(
        "pixel accuracy against the ground truth (first timed pass, every frame): %.2f %%\n\n",
        100.0 * static_cast<double>(correct_pixels) / static_cast<double>(truth_pixels));
  }
  std::printf("| stage | CPU ms median | CPU ms p95 | wall ms median |\n|---|---:|---:|---:|\n");
  for (std::size_t s = 0; s < std::size(stages); ++s) {
    std::printf("| %s | %.2f | %.2f | %.2f |\n", stages[s].first, median(cpu[s]),
                percentile(cpu[s], 95), median(wall[s]));
  }
  std::printf("| **total** | **%.2f** | %.2f | %.2f |\n", median(cpu_total),
              percentile(cpu_total, 95), median(wall_total));
  std::printf(
      "\nheap allocations per labelled frame (operator new, Segmenter::process): median %.0f "
      "calls, "
      "%.1f MB; max %.0f calls\n",
      median(news), median(megabytes), *std::max_element(news.begin(), news.end()));
  std::printf("of which (medians) prepare %.0f, oversegment %.0f, classify %.0f calls\n",
              median(news_split[0]), median(news_split[1]), median(news_split[2]));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "frame_cpu: error: %s\n", e.what());
    return 1;
  }
}
