// findmug-replay — replays recorded frames on LCM at a fixed rate, as a camera would.
//
//   findmug-replay --source 'dataset:/data/nyuv2_labeled' --rate 15 --duration 30
//                  --url 'udpm://239.255.76.67:7667?ttl=0' --count-file sent.txt
//
// The frames of any finite source (dataset folder, PCD/PCLZF/TIFF sequence,
// .oni file, or an LCM log through lcm:CHANNEL?url=file://...) are read and
// encoded once, up front, so that replaying costs almost no CPU; then they are
// published on FINDMUG_RGBD[_suffix] in a loop, one every 1/rate seconds on
// an absolute schedule (no drift), each with a fresh seq (0, 1, 2, ...) and
// utime = the host time at publication — exactly what a live camera driver
// would send, so that "label published minus frame utime" is the latency a
// client sees.
//
// lcm-logplayer replays a log at its recorded timing (and -s multiples of
// it); this tool is for fixed input rates and long looped runs (benchmarks).
// At the end it writes the number of frames published to --count-file (for
// findmug-replay-probe --expect-file) and reports frames sent late.
// --robot-pose X,Y,YAW also publishes that robot pose on FINDMUG_ROBOT_POSE[_suffix]
// just before each frame, with the frame's utime: a robot standing still, which is
// what findmugd's table map and semantic map need to take the frames in
// (benchmarks of daemon.semantic_map on recorded frames without poses).
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug_cli.hpp"
#include "findmug_signals.hpp"

namespace {

using findmug::Error;

// Set by main() to its StopSignals (made before anything starts a thread).
const findmug::cli::StopSignals* g_stop_signals = nullptr;
bool stopRequested() { return g_stop_signals != nullptr && g_stop_signals->requested(); }

void writeCount(const std::string& path, long long count) {
  // Write then rename, so that a reader polling the file never sees it half written.
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    f << count << "\n";
    if (!f) throw Error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

int run(int argc, char** argv) {
  using namespace findmug;
  std::string source_spec, suffix, count_file;
  std::string url;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) url = env;
  double rate = 0, duration = 0, warmup = 0;
  long long count = 0, max_frames = 1000;
  io::RgbdEncodeOptions encode;
  std::string depth_compression = "zlib", color_compression = "jpeg";
  std::vector<double> robot_pose;
  auto app = cli::makeApp("findmug-replay",
                          "Replays the frames of a finite source on LCM at a fixed rate, as a "
                          "camera would (fresh seq and host utime per frame)");
  cli::addSourceFlag(*app, source_spec, "frame source to replay (read and encoded up front)")
      ->required();
  cli::addLcmUrlFlag(*app, url, "LCM URL to publish on (default: LCM_DEFAULT_URL)");
  cli::addChannelSuffixFlag(*app, suffix);
  app->add_option("--rate", rate, "frames per second")
      ->required()
      ->type_name("HZ")
      ->check(CLI::Range(0.0, 1000.0))
      ->check(cli::positive());
  app->add_option("--duration", duration, "replay for S seconds")
      ->type_name("S")
      ->check(cli::positive());
  app->add_option("--count", count, "replay N frames")->type_name("N")->check(cli::positive());
  app->add_option("--max-frames", max_frames, "read at most N frames of the source")
      ->type_name("N")
      ->check(cli::positive());
  app->add_option("--depth-compression", depth_compression, "zlib or none")->type_name("C");
  app->add_option("--color-compression", color_compression, "jpeg, png or none")->type_name("C");
  app->add_option("--count-file", count_file, "write the number of frames published to F when done")
      ->type_name("F");
  app->add_option("--warmup", warmup, "wait S seconds before the first frame")
      ->type_name("S")
      ->check(CLI::Range(0.0, 3600.0));
  app->add_option("--robot-pose", robot_pose,
                  "also publish this robot pose (map frame: x, y in metres, yaw in radians) "
                  "before each frame, with its utime")
      ->type_name("X,Y,YAW")
      ->delimiter(',')
      ->expected(3);
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  encode.depth = io::parseDepthCompression(depth_compression);
  encode.color = io::parseColorCompression(color_compression);
  if ((duration > 0) == (count > 0)) throw Error("give exactly one of --duration and --count");

  // Read and encode the sequence once. The source runs as fast as it can
  // (no pacing, no loop): timing comes from the schedule below.
  io::SourceSpec spec = io::parseSourceSpec(source_spec);
  spec.options.rate_hz = 0;
  spec.options.loop = false;
  spec.options.realtime = false;
  auto source = io::makeSource(spec);
  std::vector<findmug_lcm::rgbd_frame_t> frames;
  while (static_cast<long long>(frames.size()) < max_frames) {
    std::optional<RgbdFrame> frame = source->next();
    if (!frame) break;
    frames.push_back(io::encodeRgbdFrame(*frame, encode));
  }
  const std::string described = source->describe();
  source.reset();
  if (frames.empty()) throw Error(source_spec + ": the source delivered no frames");

  // Base names: the bus applies --channel-suffix.
  const std::shared_ptr<io::Bus> bus =
      io::withChannelSuffix(std::make_shared<io::LcmBus>(url, "--lcm-url"), suffix);
  const std::string channel(io::kRgbdChannel);
  const std::string pose_channel(io::kRobotPoseChannel);
  spdlog::info("findmug-replay: {} frames from {}, {} Hz on {} ({})", frames.size(), described,
               rate, channel, bus->describe());

  using Clock = std::chrono::steady_clock;
  if (warmup > 0) std::this_thread::sleep_for(std::chrono::duration<double>(warmup));
  const auto period = std::chrono::duration<double>(1.0 / rate);
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration<double>(duration);
  long long published = 0, late = 0;
  std::vector<std::uint8_t> bytes;
  while (!stopRequested()) {
    if (count > 0 && published >= count) break;
    const auto due = start + std::chrono::duration_cast<Clock::duration>(period * published);
    if (duration > 0 && due >= end) break;
    std::this_thread::sleep_until(due);
    // More than half a period behind schedule counts as late (reported, the
    // schedule is kept: a late frame does not shift the ones after it).
    if (Clock::now() - due > period / 2) ++late;
    findmug_lcm::rgbd_frame_t& msg = frames[static_cast<std::size_t>(published) % frames.size()];
    msg.seq = published;
    msg.utime = static_cast<std::int64_t>(io::hostUtimeNow());
    if (robot_pose.size() == 3) {
      const io::RobotPose pose{static_cast<std::uint64_t>(msg.utime),
                               {robot_pose[0], robot_pose[1], robot_pose[2]}};
      bytes = io::encodeMessage(io::encodeRobotPose(pose));
      if (!bus->publish(pose_channel, bytes.data(), bytes.size())) {
        throw Error("publishing on " + pose_channel + " failed");
      }
    }
    bytes = io::encodeMessage(msg);
    if (!bus->publish(channel, bytes.data(), bytes.size())) {
      throw Error("publishing on " + channel + " failed");
    }
    ++published;
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  spdlog::info("findmug-replay: published {} frames in {:.1f} s ({:.2f} Hz), {} late", published,
               elapsed, elapsed > 0 ? published / elapsed : 0.0, late);
  if (!count_file.empty()) writeCount(count_file, published);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const findmug::cli::StopSignals stop_signals;
  g_stop_signals = &stop_signals;
  try {
    return run(argc, argv);
  } catch (const findmug::Error& e) {
    std::cerr << "findmug-replay: " << e.what() << " (see --help)\n";
    return 2;
  }
}
