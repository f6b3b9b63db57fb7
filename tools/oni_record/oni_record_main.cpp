// findmug-oni-record — records frames from any findmug frame source into an
// OpenNI .oni file that OpenNI2 (and findmug's openni2:FILE.oni source) plays.
//
//   findmug-oni-record --source 'dataset:/data/nyuv2_labeled' --out nyu.oni --rate 5
//   findmug-oni-record --source 'lcm:FINDMUG_RGBD?url=file:///tmp/rec.lcm' --out rec.oni
//                      --timestamps source
//
// Timestamps: by default frame i is stamped i / rate (--rate, default 30 Hz),
// which suits file sources read as fast as possible; --timestamps source keeps
// the spacing of the frames' own utime (live devices, LCM logs). See
// oni_writer.hpp for what the format keeps (depth, colour, field of view) and
// what it loses (principal point, camera extrinsics).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug_cli.hpp"
#include "findmug_signals.hpp"
#include "oni_writer.hpp"

namespace {

int run(int argc, char** argv) {
  using namespace findmug;
  std::string source_spec, out;
  long long count = 0;
  double rate = 30.0;
  bool source_timestamps = false;
  oni::OniWriterOptions options;
  std::string timestamps = "rate", depth_codec = "16z", color_codec = "jpeg";
  auto app = cli::makeApp("findmug-oni-record",
                          "Records frames from any findmug frame source into an OpenNI .oni file");
  cli::addSourceFlag(*app, source_spec, "frame source (see findmug-grab --help)")->required();
  app->add_option("--out", out, "the .oni file to write")->required()->type_name("FILE.oni");
  app->add_option("--count", count, "stop after N frames (0: until the source ends)")
      ->check(cli::nonNegative());
  app->add_option("--rate", rate, "stamp frame i at i/HZ seconds")
      ->check(CLI::Range(0.001, 1000.0))
      ->capture_default_str();
  app->add_option("--timestamps", timestamps,
                  "rate: i/HZ; source: the spacing of the frames' own utime")
      ->check(CLI::IsMember({"rate", "source"}))
      ->capture_default_str();
  app->add_option("--depth-codec", depth_codec, "16z or raw (lossless either way)")
      ->capture_default_str();
  app->add_option("--color-codec", color_codec, "jpeg or raw")->capture_default_str();
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  source_timestamps = timestamps == "source";
  options.depth = oni::parseDepthCodec(depth_codec);
  options.color = oni::parseColorCodec(color_codec);
  options.nominal_fps = std::max(1, std::min(120, static_cast<int>(std::lround(rate))));

  cli::StopSignals stop_signals;  // before the source starts threads
  auto source = io::makeSource(source_spec);
  std::unique_ptr<oni::OniWriter> writer;
  std::uint64_t first_utime = 0, last_stamp = 0;
  long long written = 0;
  while (!stop_signals.requested() && (count == 0 || written < count)) {
    std::optional<RgbdFrame> frame = source->next();
    if (!frame) break;
    if (!writer) {
      writer = std::make_unique<oni::OniWriter>(out, frame->width, frame->height,
                                                frame->intrinsics, options);
      first_utime = frame->utime;
    }
    std::uint64_t stamp = source_timestamps
                              ? frame->utime - std::min(first_utime, frame->utime)
                              : static_cast<std::uint64_t>(std::llround(written * 1e6 / rate));
    // Two frames with the same utime (coarse clocks) still need distinct stamps.
    if (written > 0 && stamp <= last_stamp) stamp = last_stamp + 1;
    writer->write(*frame, stamp);
    last_stamp = stamp;
    ++written;
  }
  if (!writer) throw Error(source_spec + ": the source delivered no frames");
  writer->close();
  spdlog::info("findmug-oni-record: {} frames from {} written to {}", written, source->describe(),
               out);
  return source->state() == io::SourceState::Failed ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const findmug::Error& e) {
    std::cerr << "findmug-oni-record: " << e.what() << "\n";
    return 1;
  }
}
