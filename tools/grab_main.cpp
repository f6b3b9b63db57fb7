// findmug-grab — publish RGB-D frames from any frame source on LCM.
//
//   findmug-grab --source openni2                       # the robot's camera, live
//   findmug-grab --source 'dataset:/data/nyu?rate_hz=5' --count 20
//                --url 'file:///tmp/nyu.lcm?mode=w'     (one line: an lcm-logger compatible log)
//
// Frames go out as findmug_lcm::rgbd_frame_t on FINDMUG_RGBD[_suffix] (depth zlib,
// colour JPEG by default). The LCM URL defaults to LCM's own default
// (LCM_DEFAULT_URL, else udpm with ttl 0: this machine only).
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <string>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug_cli.hpp"
#include "findmug_signals.hpp"

int main(int argc, char** argv) {
  using namespace findmug;
  using namespace findmug::io;
  std::string source_spec = "openni2";
  std::string url;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) url = env;
  std::string channel_base(kRgbdChannel);
  std::string suffix;
  RgbdEncodeOptions encode;
  double rate = -1.0;  // < 0: as the spec says
  bool loop = false;
  long long count = 0;
  bool verbose = false;
  std::string depth_compression = "zlib", color_compression = "jpeg";

  auto app = cli::makeApp("findmug-grab", "Publishes RGB-D frames from any frame source on LCM");
  cli::addSourceFlag(*app, source_spec,
                     "frame source: openni2[:URI|:FILE.oni], lcm:CHANNEL, dataset:DIR, pcd:DIR, "
                     "pclzf:DIR, tiff:DIR, with ?rate_hz=R&loop=1&realtime=0&url=URL options")
      ->capture_default_str();
  cli::addLcmUrlFlag(*app, url,
                     "LCM URL to publish on (default: LCM_DEFAULT_URL or LCM's default); "
                     "file:///path/log.lcm?mode=w writes a log file");
  app->add_option("--channel", channel_base, "base channel")->capture_default_str();
  cli::addChannelSuffixFlag(*app, suffix);
  app->add_option("--depth-compression", depth_compression, "zlib or none")->capture_default_str();
  app->add_option("--color-compression", color_compression, "jpeg, png or none")
      ->capture_default_str();
  app->add_option("--jpeg-quality", encode.jpeg_quality, "JPEG quality")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app->add_option("--rate", rate, "frames per second for file sources (overrides the spec)")
      ->check(CLI::Range(0.0, 1000.0));
  app->add_flag("--loop", loop, "loop file sources");
  app->add_option("--count", count, "stop after N frames (0: until the source ends)")
      ->check(cli::nonNegative())
      ->capture_default_str();
  app->add_flag("--verbose", verbose, "log every frame");
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  try {
    encode.depth = parseDepthCompression(depth_compression);
    encode.color = parseColorCompression(color_compression);
  } catch (const Error& e) {
    std::cerr << "findmug-grab: " << e.what() << " (see --help)\n";
    return 2;
  }

  cli::StopSignals stop_signals;  // before the source and LCM start threads
  try {
    const std::string& channel = channel_base;  // the bus applies --channel-suffix
    SourceSpec spec = parseSourceSpec(source_spec);
    if (rate >= 0) spec.options.rate_hz = rate;
    if (loop) spec.options.loop = true;
    std::unique_ptr<FrameSource> source = makeSource(spec);

    const std::shared_ptr<Bus> bus =
        withChannelSuffix(std::make_shared<LcmBus>(url, "--lcm-url"), suffix);
    spdlog::info("findmug-grab: {} -> {} on {}", source->describe(), channel, bus->describe());

    // The source may block in next(); a stop signal turns into stop().
    const auto stop_registration = stop_signals.onStop([&source] { source->stop(); });

    long long published = 0;
    std::size_t bytes = 0;
    int exit_code = 0;
    try {
      while (count == 0 || published < count) {
        std::optional<RgbdFrame> frame = source->next();
        if (!frame) break;
        const findmug_lcm::rgbd_frame_t msg = encodeRgbdFrame(*frame, encode);
        const std::vector<std::uint8_t> data = encodeMessage(msg);
        if (!bus->publish(channel, data.data(), data.size())) {
          throw Error("publishing on " + channel + " failed");
        }
        ++published;
        bytes += data.size();
        if (verbose) {
          spdlog::info("frame {} seq {} {}x{}: {} bytes", published, frame->seq, frame->width,
                       frame->height, data.size());
        }
      }
    } catch (const Error& e) {
      spdlog::error("findmug-grab: {}", e.what());
      exit_code = 1;
    }
    const SourceStats stats = source->stats();
    spdlog::info("findmug-grab: published {} frames ({:.1f} MB); source {} ({} rejected)",
                 published, bytes / 1e6, sourceStateName(source->state()), stats.frames_rejected);
    if (exit_code == 0 && source->state() == SourceState::Failed) exit_code = 1;
    return exit_code;
  } catch (const Error& e) {
    std::cerr << "findmug-grab: " << e.what() << "\n";
    return 1;
  }
}
