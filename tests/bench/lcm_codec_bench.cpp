// LCM codec cost per 640x480 NYU frame: the daemon decodes every incoming
// rgbd_frame_t and findmug-grab encodes every outgoing one, so at 30 fps both
// must stay far below 33 ms. Also the wire check alone (decodeMessage), which
// runs before LCM's generated decode.
#include <benchmark/benchmark.h>

#include "findmug/dataset.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "test_data.hpp"

namespace {

using namespace findmug;
using namespace findmug::io;

const RgbdFrame* nyuFrame() {
  static const RgbdFrame* frame = []() -> const RgbdFrame* {
    const auto dir = test::dataPath("nyuv2_labeled");
    if (dir.empty()) return nullptr;
    return new RgbdFrame(DatasetFolder(dir.string()).load(0).frame);
  }();
  return frame;
}

RgbdEncodeOptions options(int color) {
  RgbdEncodeOptions o;
  o.depth = DepthCompression::Zlib;
  o.color = static_cast<ColorCompression>(color);
  return o;
}

void BM_EncodeRgbd(benchmark::State& state) {
  const RgbdFrame* frame = nyuFrame();
  if (!frame) return state.SkipWithError("nyuv2_labeled missing (FINDMUG_DATA)");
  std::size_t bytes = 0;
  for (auto _ : state) {
    const auto data =
        encodeMessage(encodeRgbdFrame(*frame, options(static_cast<int>(state.range(0)))));
    bytes = data.size();
    benchmark::DoNotOptimize(data.data());
  }
  state.counters["message_kB"] = static_cast<double>(bytes) / 1000.0;
}

void BM_DecodeRgbd(benchmark::State& state) {
  const RgbdFrame* frame = nyuFrame();
  if (!frame) return state.SkipWithError("nyuv2_labeled missing (FINDMUG_DATA)");
  const auto data =
      encodeMessage(encodeRgbdFrame(*frame, options(static_cast<int>(state.range(0)))));
  for (auto _ : state) {
    RgbdFrame out = decodeRgbdFrame(data.data(), data.size(), "FINDMUG_RGBD");
    benchmark::DoNotOptimize(out.depth_mm.data());
  }
}

void BM_WireCheckAndLcmDecode(benchmark::State& state) {
  const RgbdFrame* frame = nyuFrame();
  if (!frame) return state.SkipWithError("nyuv2_labeled missing (FINDMUG_DATA)");
  const auto data = encodeMessage(encodeRgbdFrame(*frame, options(1)));
  for (auto _ : state) {
    rgbd_frame_t msg = decodeMessage<rgbd_frame_t>(data.data(), data.size(), "FINDMUG_RGBD");
    benchmark::DoNotOptimize(msg.depth_data.data());
  }
}

// Argument: colour compression 0 none, 1 JPEG, 2 PNG (depth always zlib).
BENCHMARK(BM_EncodeRgbd)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeRgbd)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WireCheckAndLcmDecode)->Unit(benchmark::kMicrosecond);

}  // namespace
