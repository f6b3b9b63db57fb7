// findmug-grab — publish RGB-D frames from any frame source on LCM.
//
//   findmug-grab --source openni2                       # the robot's camera, live
//   findmug-grab --source 'dataset:/data/nyu?rate_hz=5' --count 20
//                --url 'file:///tmp/nyu.lcm?mode=w'     (one line: an lcm-logger compatible log)
//
// Frames go out as findmug::rgbd_frame_t on FINDMUG_RGBD[_suffix] (depth zlib,
// colour JPEG by default). The LCM URL defaults to LCM's own default
// (LCM_DEFAULT_URL, else udpm with ttl 0: this machine only).
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>

#include "tool_common.hpp"
#include "findmug/error.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"

namespace {

std::atomic<bool> g_interrupted{false};
void onSignal(int) { g_interrupted = true; }

void usage(std::ostream& out) {
  out << "usage: findmug-grab [options]\n"
         "  --source SPEC           frame source (default openni2): openni2[:URI|:FILE.oni],\n"
         "                          lcm:CHANNEL, dataset:DIR, pcd:DIR, pclzf:DIR, tiff:DIR,\n"
         "                          with ?rate_hz=R&loop=1&realtime=0&url=URL options\n"
         "  --url URL               LCM URL to publish on (default: LCM_DEFAULT_URL or LCM's\n"
         "                          default); file:///path/log.lcm?mode=w writes a log file\n"
         "  --channel NAME          base channel (default FINDMUG_RGBD)\n"
         "  --channel-suffix S      appended as NAME_S\n"
         "  --depth-compression C   zlib (default) or none\n"
         "  --color-compression C   jpeg (default), png or none\n"
         "  --jpeg-quality Q        1..100 (default 90)\n"
         "  --rate HZ               frames per second for file sources (overrides the spec)\n"
         "  --loop                  loop file sources\n"
         "  --count N               stop after N frames (default 0 = until the source ends)\n"
         "  --verbose               log every frame\n";
}


}  // namespace

int main(int argc, char** argv) {
  using namespace findmug;
  using namespace findmug::io;
  std::string source_spec = "openni2";
  std::string url;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) url = env;
  std::string channel_base(kRgbdChannel);
  std::string suffix;
  RgbdEncodeOptions encode;
  std::optional<double> rate;
  bool loop = false;
  long long count = 0;
  bool verbose = false;

  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw Error(arg + " needs a value");
        return argv[++i];
      };
      if (arg == "--help" || arg == "-h") {
        usage(std::cout);
        return 0;
      } else if (arg == "--source") {
        source_spec = value();
      } else if (arg == "--url") {
        url = value();
      } else if (arg == "--channel") {
        channel_base = value();
      } else if (arg == "--channel-suffix") {
        suffix = value();
      } else if (arg == "--depth-compression") {
        encode.depth = parseDepthCompression(value());
      } else if (arg == "--color-compression") {
        encode.color = parseColorCompression(value());
      } else if (arg == "--jpeg-quality") {
        const double q = findmug::tools::parseNumber(arg, value());
        if (q < 1 || q > 100) throw Error("--jpeg-quality must be 1..100");
        encode.jpeg_quality = static_cast<int>(q);
      } else if (arg == "--rate") {
        rate = findmug::tools::parseNumber(arg, value());
        if (*rate < 0 || *rate > 1000) throw Error("--rate must be 0..1000 Hz");
      } else if (arg == "--loop") {
        loop = true;
      } else if (arg == "--count") {
        const double c = findmug::tools::parseNumber(arg, value());
        if (c < 0 || c != static_cast<double>(static_cast<long long>(c))) {
          throw Error("--count must be a non-negative integer");
        }
        count = static_cast<long long>(c);
      } else if (arg == "--verbose") {
        verbose = true;
      } else {
        throw Error("unknown argument '" + arg + "'");
      }
    }
  } catch (const Error& e) {
    std::cerr << "findmug-grab: " << e.what() << "\n";
    usage(std::cerr);
    return 2;
  }

  try {
    const std::string channel = channelName(channel_base, suffix);
    SourceSpec spec = parseSourceSpec(source_spec);
    if (rate) spec.options.rate_hz = *rate;
    if (loop) spec.options.loop = true;
    std::unique_ptr<FrameSource> source = makeSource(spec);

    lcm::LCM lcm(url);
    if (!lcm.good()) throw Error("cannot open LCM URL '" + url + "'");
    spdlog::info("findmug-grab: {} -> {} on {}", source->describe(), channel,
                 url.empty() ? std::string("LCM default URL") : url);

    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    // The source may block in next(); a watcher turns a signal into stop().
    std::atomic<bool> done{false};
    std::thread watcher([&] {
      while (!done) {
        if (g_interrupted) {
          source->stop();
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    });

    long long published = 0;
    std::size_t bytes = 0;
    int exit_code = 0;
    try {
      while (count == 0 || published < count) {
        std::optional<RgbdFrame> frame = source->next();
        if (!frame) break;
        const rgbd_frame_t msg = encodeRgbdFrame(*frame, encode);
        const std::vector<std::uint8_t> data = encodeMessage(msg);
        if (lcm.publish(channel, data.data(), static_cast<unsigned int>(data.size())) != 0) {
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
    done = true;
    watcher.join();
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
