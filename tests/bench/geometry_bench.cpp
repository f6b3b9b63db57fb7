// geometry_bench: the geometric front of the pipeline on one real 640x480
// NYU Depth V2 frame (raw Kinect depth with holes, frame 0433):
// back-projection, normals, ground plane (from labels and estimated),
// transform into the ground frame, the organized oversegmentation, and the
// 14-D features of ~1000 patches;
// then, on the frame's own oversegmentation, the 14-D features, the region
// features both ways (from the pixels, and from the 14-D features' moments
// as the pipeline does) and the scene features.
//
//   geometry_bench [--benchmark_filter=REGEX]
//
// Data from $FINDMUG_DATA or ../shared/data (nyuv2_labeled/).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "findmug/cloud/cloud.hpp"
#include "findmug/features/features.hpp"
#include "findmug/features/region_features.hpp"
#include "findmug/features/scene_features.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "oversegmentation/lab_internal.hpp"
#include "test_data.hpp"

namespace {

using namespace findmug;

struct Fixture {
  RgbdFrame frame;
  std::vector<std::uint8_t> labels;
  OrganizedCloud cloud;
  NormalImage normals;
  GroundPlane ground;
  OrganizedCloud cloud_ground;
  NormalImage normals_ground;
  Oversegmentation blocks;  // 20x16-pixel blocks: 960 patches, as many as supervoxels
  Oversegmentation segmentation;  // the organized oversegmenter's, with its adjacency
  SegmentFeatures features;       // of `segmentation`
};

// Loads once; throws when the data is missing (reported per benchmark).
const Fixture& fixture() {
  static const Fixture f = [] {
    const auto dir = findmug::test::dataRoot() / "nyuv2_labeled";
    const std::string name = "0433";
    Fixture x;
    const auto depth = readPng16((dir / "depth" / (name + ".png")).string());
    const auto rgb = readPngRgb((dir / "rgb" / (name + ".png")).string());
    x.labels = readPng8((dir / "label8" / (name + ".png")).string()).pixels;
    x.frame.width = depth.width;
    x.frame.height = depth.height;
    x.frame.depth_mm = depth.pixels;
    x.frame.rgb = rgb.pixels;
    x.frame.intrinsics = kNyuIntrinsics;
    x.frame.source = name;
    x.cloud = frameToCloud(x.frame);
    x.normals = computeNormals(x.cloud, NormalConfig{});
    const auto g = fitGroundToLabels(x.cloud, x.labels, GroundConfig{});
    if (!g) throw std::runtime_error("no floor plane in " + name);
    x.ground = *g;
    x.cloud_ground = transformCloud(x.cloud, x.ground.camera_to_ground);
    x.normals_ground = rotateNormals(x.normals, x.ground.camera_to_ground.linear());

    auto& seg = x.blocks;
    seg.width = x.cloud.width;
    seg.height = x.cloud.height;
    seg.pixel_segment.assign(x.cloud.size(), -1);
    const int bw = 20, bh = 16, cols = seg.width / bw;
    std::vector<int> block_to_segment(static_cast<std::size_t>(cols) * (seg.height / bh), -1);
    for (int v = 0; v < seg.height; ++v) {
      for (int u = 0; u < seg.width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * seg.width + u;
        if (!x.cloud.valid(i)) continue;
        int& s = block_to_segment[static_cast<std::size_t>(v / bh) * cols + u / bw];
        if (s < 0) {
          s = static_cast<int>(seg.segments.size());
          seg.segments.emplace_back();
        }
        seg.pixel_segment[i] = s;
        seg.segments[s].push_back(static_cast<int>(i));
      }
    }
    x.segmentation = makeOversegmenter(OversegmentationConfig{})->segment(x.cloud, x.normals);
    x.features = computeFeatures(x.cloud_ground, x.normals_ground, x.segmentation);
    return x;
  }();
  return f;
}

template <typename Body>
void run(benchmark::State& state, Body body) {
  const Fixture* f = nullptr;
  try {
    f = &fixture();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  for (auto _ : state) body(*f);
}

void BM_FrameToCloud(benchmark::State& state) {
  run(state, [](const Fixture& f) { benchmark::DoNotOptimize(frameToCloud(f.frame)); });
}
BENCHMARK(BM_FrameToCloud)->Unit(benchmark::kMillisecond);

void BM_ComputeNormals(benchmark::State& state) {
  run(state,
      [](const Fixture& f) { benchmark::DoNotOptimize(computeNormals(f.cloud, NormalConfig{})); });
}
BENCHMARK(BM_ComputeNormals)->Unit(benchmark::kMillisecond);

void BM_FitGroundToLabels(benchmark::State& state) {
  run(state, [](const Fixture& f) {
    benchmark::DoNotOptimize(fitGroundToLabels(f.cloud, f.labels, GroundConfig{}));
  });
}
BENCHMARK(BM_FitGroundToLabels)->Unit(benchmark::kMillisecond);

void BM_EstimateGround(benchmark::State& state) {
  run(state, [](const Fixture& f) {
    benchmark::DoNotOptimize(estimateGround(f.cloud, f.normals, GroundConfig{}));
  });
}
BENCHMARK(BM_EstimateGround)->Unit(benchmark::kMillisecond);

void BM_TransformToGround(benchmark::State& state) {
  run(state, [](const Fixture& f) {
    benchmark::DoNotOptimize(transformCloud(f.cloud, f.ground.camera_to_ground));
    benchmark::DoNotOptimize(rotateNormals(f.normals, f.ground.camera_to_ground.linear()));
  });
}
BENCHMARK(BM_TransformToGround)->Unit(benchmark::kMillisecond);

void BM_OversegmentOrganized(benchmark::State& state) {
  // Into a recycled result, as the pipeline does: the pixel lists keep
  // their capacity.
  const auto oversegmenter = makeOversegmenter(OversegmentationConfig{});
  Oversegmentation out;
  run(state, [&](const Fixture& f) {
    oversegmenter->segmentInto(f.cloud, f.normals, out);
    benchmark::DoNotOptimize(out.pixel_segment.data());
    state.counters["segments"] = static_cast<double>(out.segments.size());
  });
}
BENCHMARK(BM_OversegmentOrganized)->Unit(benchmark::kMillisecond);

// The oversegmenters' last step alone (range check, counts, renumbering,
// pixel lists, adjacency) on the organized oversegmentation of the frame;
// the copy of its ids into the recycled result is included (about 0.1 ms).
void BM_FinalizeOversegmentation(benchmark::State& state) {
  Oversegmentation out;
  run(state, [&](const Fixture& f) {
    out.width = f.segmentation.width;
    out.height = f.segmentation.height;
    out.pixel_segment.assign(f.segmentation.pixel_segment.begin(),
                             f.segmentation.pixel_segment.end());
    finalizeOversegmentation(out, OversegmentationConfig{}.min_segment_points);
    benchmark::DoNotOptimize(out.edges.data());
  });
}
BENCHMARK(BM_FinalizeOversegmentation)->Unit(benchmark::kMillisecond);

// The oversegmenter's sRGB -> CIELAB of every pixel of the frame, with the
// AVX2 path (Auto) and without (Off).
void labOfEveryPixel(benchmark::State& state, detail::LabSimd simd) {
  std::vector<int> pixel;
  std::vector<float> lab;
  run(state, [&](const Fixture& f) {
    if (pixel.empty()) {
      pixel.resize(f.cloud.size());
      for (std::size_t i = 0; i < pixel.size(); ++i) pixel[i] = static_cast<int>(i);
      lab.resize(3 * pixel.size());
    }
    float* l = lab.data();
    detail::labFromRgb(f.cloud.colors.data(), pixel.data(), pixel.size(), l, l + pixel.size(),
                       l + 2 * pixel.size(), simd);
    benchmark::DoNotOptimize(l);
  });
}
void BM_LabFromRgbAuto(benchmark::State& state) { labOfEveryPixel(state, detail::LabSimd::Auto); }
void BM_LabFromRgbScalar(benchmark::State& state) { labOfEveryPixel(state, detail::LabSimd::Off); }
BENCHMARK(BM_LabFromRgbAuto)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LabFromRgbScalar)->Unit(benchmark::kMillisecond);

void BM_ComputeFeatures(benchmark::State& state) {
  run(state, [&state](const Fixture& f) {
    benchmark::DoNotOptimize(computeFeatures(f.cloud_ground, f.normals_ground, f.blocks));
    state.counters["segments"] = static_cast<double>(f.blocks.segments.size());
  });
}
BENCHMARK(BM_ComputeFeatures)->Unit(benchmark::kMillisecond);

void BM_ComputeFeaturesOversegmented(benchmark::State& state) {
  SegmentFeatures out;
  run(state, [&](const Fixture& f) {
    computeFeaturesInto(f.cloud_ground, f.normals_ground, f.segmentation, out);
    benchmark::DoNotOptimize(out.features.data());
    state.counters["segments"] = static_cast<double>(f.segmentation.segments.size());
  });
}
BENCHMARK(BM_ComputeFeaturesOversegmented)->Unit(benchmark::kMillisecond);

void BM_RegionFeaturesFromPixels(benchmark::State& state) {
  RegionFeatures out;
  run(state, [&](const Fixture& f) {
    computeRegionFeaturesInto(f.cloud_ground, f.normals_ground, f.segmentation, RegionConfig{},
                              out);
    benchmark::DoNotOptimize(out.values.data());
  });
}
BENCHMARK(BM_RegionFeaturesFromPixels)->Unit(benchmark::kMillisecond);

void BM_RegionFeaturesFromMoments(benchmark::State& state) {
  RegionFeatures out;
  run(state, [&](const Fixture& f) {
    computeRegionFeaturesInto(f.features, f.segmentation, RegionConfig{}, out);
    benchmark::DoNotOptimize(out.values.data());
    state.counters["regions"] = out.region_count;
  });
}
BENCHMARK(BM_RegionFeaturesFromMoments)->Unit(benchmark::kMillisecond);

void BM_SceneFeatures(benchmark::State& state) {
  std::vector<float> out;
  run(state, [&](const Fixture& f) {
    computeSceneFeaturesInto(f.cloud_ground, f.segmentation, f.features,
                             f.ground.camera_to_ground.translation(), SceneConfig{}, out);
    benchmark::DoNotOptimize(out.data());
  });
}
BENCHMARK(BM_SceneFeatures)->Unit(benchmark::kMillisecond);

}  // namespace
