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
#include <csignal>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "tool_common.hpp"
#include "findmug/error.hpp"
#include "findmug/io/frame_source.hpp"
#include "oni_writer.hpp"

namespace {

std::atomic<bool> g_interrupted{false};
void onSignal(int) { g_interrupted = true; }

const char* kUsage =
    "usage: findmug-oni-record --source SPEC --out FILE.oni [options]\n"
    "  --count N                 stop after N frames (default: until the source ends)\n"
    "  --rate HZ                 stamp frame i at i/HZ seconds (default 30)\n"
    "  --timestamps source       use the spacing of the frames' own utime instead\n"
    "  --depth-codec 16z|raw     lossless either way (default 16z)\n"
    "  --color-codec jpeg|raw    (default jpeg)\n";


int run(int argc, char** argv) {
  using namespace findmug;
  std::string source_spec, out;
  long long count = 0;
  double rate = 30.0;
  bool source_timestamps = false;
  oni::OniWriterOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage;
      return 0;
    } else if (arg == "--source") {
      source_spec = value();
    } else if (arg == "--out") {
      out = value();
    } else if (arg == "--count") {
      const double c = findmug::tools::parseNumber(arg, value());
      if (c < 0 || c != static_cast<double>(static_cast<long long>(c))) {
        throw Error("--count must be a non-negative integer");
      }
      count = static_cast<long long>(c);
    } else if (arg == "--rate") {
      rate = findmug::tools::parseNumber(arg, value());
      if (!(rate > 0 && rate <= 1000)) throw Error("--rate must be in (0, 1000] Hz");
    } else if (arg == "--timestamps") {
      const std::string v = value();
      if (v != "source" && v != "rate") throw Error("--timestamps must be source or rate");
      source_timestamps = v == "source";
    } else if (arg == "--depth-codec") {
      options.depth = oni::parseDepthCodec(value());
    } else if (arg == "--color-codec") {
      options.color = oni::parseColorCodec(value());
    } else {
      throw Error("unknown argument '" + arg + "'");
    }
  }
  if (source_spec.empty() || out.empty()) throw Error("--source and --out are required");
  options.nominal_fps = std::max(1, std::min(120, static_cast<int>(std::lround(rate))));

  auto source = io::makeSource(source_spec);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  std::unique_ptr<oni::OniWriter> writer;
  std::uint64_t first_utime = 0, last_stamp = 0;
  long long written = 0;
  while (!g_interrupted && (count == 0 || written < count)) {
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
