// LCM codec cost per 640x480 NYU frame: the daemon decodes every incoming
// rgbd_frame_t and findmug-grab encodes every outgoing one, so at 30 fps both
// must stay far below 33 ms. Also the wire check alone (decodeMessage), which
// runs before LCM's generated decode.
#include <benchmark/benchmark.h>
#include <zlib.h>

#include <cmath>

#include "findmug/frame/dataset.hpp"
#include "compression.hpp"  // io/src: the label images' own deflate
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
    findmug_lcm::rgbd_frame_t msg =
        decodeMessage<findmug_lcm::rgbd_frame_t>(data.data(), data.size(), "FINDMUG_RGBD");
    benchmark::DoNotOptimize(msg.depth_data.data());
  }
}

// Label image of NYU frame 0 (its ground-truth labels, void as the daemon
// sends it) and a confidence image constant per label, quantised to bytes as
// encodeLabelImage does: the daemon's label images are piecewise constant
// the same way (one label and confidence per segment).
const std::vector<std::uint8_t>* labelBytes(bool confidence) {
  static const std::vector<std::uint8_t>* images = []() -> const std::vector<std::uint8_t>* {
    const auto dir = test::dataPath("nyuv2_labeled");
    if (dir.empty()) return nullptr;
    auto* out = new std::vector<std::uint8_t>[2];
    out[0] = DatasetFolder(dir.string()).load(0).labels;
    out[1].resize(out[0].size());
    for (std::size_t i = 0; i < out[0].size(); ++i) {
      out[1][i] = static_cast<std::uint8_t>(std::lround((0.4f + 0.07f * (out[0][i] % 8)) * 255.0f));
    }
    return out;
  }();
  return images ? &images[confidence ? 1 : 0] : nullptr;
}

// Deflate of the label and confidence bytes of one label image: argument
// 0 = zlib level 1, default strategy (the encoder up to 4f88746), 1 = zlib
// level 1, Z_RLE (the encoder up to 03432c5), 2 = the io library's own
// zlibCompressRuns (the encoder now). All inflate with the same decoder.
void BM_DeflateLabelImage(benchmark::State& state) {
  const auto* labels = labelBytes(false);
  const auto* confidence = labelBytes(true);
  if (!labels) return state.SkipWithError("nyuv2_labeled missing (FINDMUG_DATA)");
  const int strategy = state.range(0) == 0 ? Z_DEFAULT_STRATEGY : Z_RLE;
  std::vector<std::uint8_t> out(compressBound(static_cast<uLong>(labels->size())));
  std::size_t bytes = 0;
  if (state.range(0) == 2) {
    for (auto _ : state) {
      bytes = 0;
      for (const auto* image : {labels, confidence}) {
        const std::vector<std::uint8_t> stream =
            detail::zlibCompressRuns(image->data(), image->size());
        bytes += stream.size();
        benchmark::DoNotOptimize(stream.data());
      }
    }
    state.counters["compressed_kB"] = static_cast<double>(bytes) / 1000.0;
    return;
  }
  for (auto _ : state) {
    bytes = 0;
    for (const auto* image : {labels, confidence}) {
      z_stream zs{};
      deflateInit2(&zs, 1, Z_DEFLATED, 15, 8, strategy);
      zs.next_in = const_cast<Bytef*>(image->data());
      zs.avail_in = static_cast<uInt>(image->size());
      zs.next_out = out.data();
      zs.avail_out = static_cast<uInt>(out.size());
      if (deflate(&zs, Z_FINISH) != Z_STREAM_END) state.SkipWithError("deflate failed");
      bytes += zs.total_out;
      deflateEnd(&zs);
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.counters["compressed_kB"] = static_cast<double>(bytes) / 1000.0;
}

// encodeLabelImage as the daemon calls it for every frame: NYU frame 0's
// labels with a confidence constant per label (validation, quantisation,
// the two deflates).
void BM_EncodeLabelImage(benchmark::State& state) {
  const auto* labels = labelBytes(false);
  const auto* confidence = labelBytes(true);
  if (!labels) return state.SkipWithError("nyuv2_labeled missing (FINDMUG_DATA)");
  LabelImageMessage message;
  message.image.width = 640;
  message.image.height = static_cast<int>(labels->size() / 640);
  message.image.labels = *labels;
  for (const std::uint8_t q : *confidence) message.image.confidence.push_back(q / 255.0f);
  std::size_t bytes = 0;
  for (auto _ : state) {
    const findmug_lcm::label_image_t msg = encodeLabelImage(message, true);
    bytes = msg.labels_data.size() + msg.confidence_data.size();
    benchmark::DoNotOptimize(msg.labels_data.data());
  }
  state.counters["compressed_kB"] = static_cast<double>(bytes) / 1000.0;
}

// Argument: colour compression 0 none, 1 JPEG, 2 PNG (depth always zlib).
BENCHMARK(BM_EncodeRgbd)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeRgbd)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DeflateLabelImage)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WireCheckAndLcmDecode)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EncodeLabelImage)->Unit(benchmark::kMillisecond);

}  // namespace
