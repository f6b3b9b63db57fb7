// findmug-synth: renders a synthetic apartment sequence into the dataset
// folder layout the trainer reads (rgb/, depth/, label8/, intrinsics.yaml,
// extrinsics.csv) plus ground_truth.yaml (camera poses and tables).
//
//   findmug-synth --seed 7 --frames 300 --out /tmp/synth7 [--fps 30]
//                 [--camera-height 1.0:1.4] [--pitch-deg 20:45] [--tables 1:3]
//                 [--speed 0.4] [--no-noise]
#include <cstdio>
#include <iostream>
#include <string>
#include <tuple>

#include "findmug/error.hpp"
#include "findmug/synth.hpp"
#include "findmug/dataset.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "tool_common.hpp"

#include <lcm/lcm-cpp.hpp>

namespace {

constexpr const char* kUsage =
    "usage: findmug-synth --seed N --frames N --out DIR [options]\n"
    "  --seed N              scene/path/noise seed (same seed, same bytes)\n"
    "  --frames N            number of frames to render\n"
    "  --out DIR             output dataset folder (must be empty or absent)\n"
    "  --fps F               frame rate of the camera path (default 30)\n"
    "  --camera-height A:B   camera height range in metres (default 1.0:1.4; A alone = fixed)\n"
    "  --pitch-deg A:B       camera tilt-down range in degrees (default 20:45)\n"
    "  --tables A:B          number of tables (default 1:3)\n"
    "  --speed V             robot speed in m/s (default 0.4)\n"
    "  --no-noise            exact depth (mm), no dropouts, no colour noise\n"
    "  --lcm-log FILE        also write the frames as an LCM log of rgbd_frame_t on\n"
    "                        FINDMUG_RGBD (what lcm-logplayer replays to findmugd), stamped\n"
    "                        with the sequence's own frame times\n";


// "A:B" or "A" (then B = A).
std::pair<double, double> parseRange(const std::string& flag, const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    const double v = findmug::tools::parseNumber("--" + flag, text);
    return {v, v};
  }
  return {findmug::tools::parseNumber("--" + flag, text.substr(0, colon)),
          findmug::tools::parseNumber("--" + flag, text.substr(colon + 1))};
}

std::uint64_t parseSeed(const std::string& text) {
  try {
    std::size_t used = 0;
    if (!text.empty() && text[0] != '-') {
      const unsigned long long v = std::stoull(text, &used);
      if (used == text.size()) return v;
    }
  } catch (const std::exception&) {
  }
  throw findmug::Error("flag --seed: '" + text + "' is not a non-negative integer");
}

// The written folder as an LCM log, read back through the dataset reader so
// the log holds exactly what the folder holds. Each event carries the
// frame's own time, so lcm-logplayer replays at the sequence's frame rate.
void writeLcmLog(const std::string& dataset_dir, const findmug::synth::SequenceGroundTruth& truth,
                 const std::string& log_path) {
  using namespace findmug;
  const DatasetFolder folder(dataset_dir);
  lcm::LogFile log(log_path, "w");
  if (!log.good()) throw Error(log_path + ": cannot open the LCM log for writing");
  const std::string channel(io::kRgbdChannel);
  for (std::size_t i = 0; i < folder.size(); ++i) {
    LabeledFrame frame = folder.load(i);
    frame.frame.seq = static_cast<std::int64_t>(i);
    if (i < truth.frame_utimes.size()) frame.frame.utime = truth.frame_utimes[i];
    const rgbd_frame_t message = io::encodeRgbdFrame(frame.frame);
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
    if (message.encode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0)
      throw Error(log_path + ": cannot encode frame " + frame.name);
    lcm::LogEvent event;
    event.eventnum = static_cast<int64_t>(i);
    event.timestamp = static_cast<int64_t>(frame.frame.utime);
    event.channel = channel;
    event.datalen = static_cast<int32_t>(bytes.size());
    event.data = bytes.data();
    if (log.writeEvent(&event) != 0) throw Error(log_path + ": write failed at frame " + frame.name);
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace findmug;
  try {
    const tools::Flags flags(argc, argv, {"no-noise", "help"});
    if (flags.has("help")) {
      std::cout << kUsage;
      return 0;
    }
    flags.allowOnly({"seed", "frames", "out", "fps", "camera-height", "pitch-deg", "tables",
                     "speed", "no-noise", "lcm-log", "help"});
    for (const char* required : {"seed", "frames", "out"})
      if (!flags.has(required)) throw Error(std::string("missing --") + required + "\n" + kUsage);

    synth::SequenceSpec spec;
    spec.seed = parseSeed(flags.get("seed"));
    spec.frames = flags.getInt("frames", 0);
    if (spec.frames <= 0)
      throw Error("flag --frames: must be positive, got " + flags.get("frames"));
    if (flags.has("fps")) spec.fps = findmug::tools::parseNumber("--fps", flags.get("fps"));
    if (flags.has("camera-height"))
      std::tie(spec.path.height_min, spec.path.height_max) =
          parseRange("camera-height", flags.get("camera-height"));
    if (flags.has("pitch-deg"))
      std::tie(spec.path.pitch_min_deg, spec.path.pitch_max_deg) =
          parseRange("pitch-deg", flags.get("pitch-deg"));
    if (flags.has("tables")) {
      const auto [lo, hi] = parseRange("tables", flags.get("tables"));
      if (lo != static_cast<int>(lo) || hi != static_cast<int>(hi))
        throw Error("flag --tables: '" + flags.get("tables") + "' must be integers");
      spec.apartment.tables_min = static_cast<int>(lo);
      spec.apartment.tables_max = static_cast<int>(hi);
    }
    if (flags.has("speed")) spec.path.speed_mps = findmug::tools::parseNumber("--speed", flags.get("speed"));
    if (flags.has("no-noise")) {
      spec.render.noise.enabled = false;
      spec.render.noise.rgb_noise_sigma = 0.0;
    }

    const std::string out = flags.get("out");
    tools::ProgressBar bar("findmug-synth");
    const auto truth =
        synth::writeSequence(out, spec, [&](int done, int total) { bar.update(done, total); });
    bar.finish();
    std::printf("wrote %d frames (%d table%s) to %s, ground truth in %s/ground_truth.yaml\n",
                spec.frames, static_cast<int>(truth.tables.size()),
                truth.tables.size() == 1 ? "" : "s", out.c_str(), out.c_str());
    if (flags.has("lcm-log")) {
      writeLcmLog(out, truth, flags.get("lcm-log"));
      std::printf("wrote %d rgbd_frame_t messages on %s to %s\n", spec.frames,
                  std::string(io::kRgbdChannel).c_str(), flags.get("lcm-log").c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "findmug-synth: %s\n", e.what());
    return 1;
  }
}
