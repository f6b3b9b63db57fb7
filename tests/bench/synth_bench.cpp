// Benchmarks of the synthetic generator. The figure that matters is
// BM_RenderFrame: one 640x480 frame with the full Kinect noise model on one
// core (target: median <= 50 ms). Frames cycle over a 30-frame camera path so
// near and far views are both measured.
//
//   synth_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include "findmug/synth/synth.hpp"

namespace {

using namespace findmug::synth;

void renderLoop(benchmark::State& state, const RenderOptions& options) {
  const SynthScene scene = makeApartment(static_cast<std::uint64_t>(state.range(0)));
  const auto poses = cameraPath(scene, 30, 1.0);
  std::size_t i = 0;
  for (auto _ : state) {
    RenderedFrame r = render(scene, poses[i % poses.size()], options, i);
    benchmark::DoNotOptimize(r.labeled.frame.depth_mm.data());
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_RenderFrame(benchmark::State& state) { renderLoop(state, RenderOptions{}); }
BENCHMARK(BM_RenderFrame)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

void BM_RenderFrameExact(benchmark::State& state) {
  RenderOptions options;
  options.noise.enabled = false;
  options.noise.rgb_noise_sigma = 0.0;
  renderLoop(state, options);
}
BENCHMARK(BM_RenderFrameExact)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_MakeApartment(benchmark::State& state) {
  std::uint64_t seed = 1;
  for (auto _ : state) {
    SynthScene scene = makeApartment(seed++);
    benchmark::DoNotOptimize(scene.primitives.data());
  }
}
BENCHMARK(BM_MakeApartment)->Unit(benchmark::kMillisecond);

void BM_CameraPath300(benchmark::State& state) {
  const SynthScene scene = makeApartment(1);
  for (auto _ : state) {
    auto poses = cameraPath(scene, 300, 30.0);
    benchmark::DoNotOptimize(poses.data());
  }
}
BENCHMARK(BM_CameraPath300)->Unit(benchmark::kMillisecond);

}  // namespace
