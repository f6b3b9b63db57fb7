// findmug-synth: renders a synthetic apartment sequence into the dataset
// folder layout the trainer reads (rgb/, depth/, label8/, intrinsics.yaml,
// extrinsics.csv) plus ground_truth.yaml (camera poses and tables).
//
//   findmug-synth --seed 7 --frames 300 --out /tmp/synth7 [--fps 30]
//                 [--camera-height 1.0:1.4] [--pitch-deg 20:45] [--tables 1:3]
//                 [--speed 0.4] [--no-noise]
//   findmug-synth --multi-room --seed 9001 --frames 200 --out /tmp/rooms9001 [--fps 2]
//
// --multi-room renders the search bench's multi-room apartments (beds, sofas, shelves),
// one view of a piece of furniture a frame (synth::apartmentViews), for a model to learn
// the object search's domain.
#include <cstdio>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <tuple>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/synth/synth.hpp"
#include "findmug_cli.hpp"
#include "tool_common.hpp"

namespace {

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
  if (const auto v = findmug::parseUnsigned(text)) return *v;
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
    const findmug_lcm::rgbd_frame_t message = io::encodeRgbdFrame(frame.frame);
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
  std::string seed_text, out, fps_text, height_text, pitch_text, tables_text, speed_text, lcm_log;
  int frames = 0;
  bool no_noise = false;
  bool multi_room = false;
  auto app = cli::makeApp("findmug-synth",
                          "Renders a synthetic apartment sequence with ground truth into a "
                          "dataset folder (rgb/, depth/, label8/, intrinsics.yaml, "
                          "extrinsics.csv, ground_truth.yaml)");
  app->add_option("--seed", seed_text, "scene/path/noise seed (same seed, same bytes)")
      ->required()
      ->type_name("N");
  app->add_option("--frames", frames, "number of frames to render")
      ->required()
      ->check(cli::positive());
  app->add_option("--out", out, "output dataset folder (must be empty or absent)")
      ->required()
      ->type_name("DIR");
  app->add_option("--fps", fps_text, "frame rate of the camera path (default 30)")->type_name("F");
  app->add_option("--camera-height", height_text,
                  "camera height range in metres (default 1.0:1.4; A alone = fixed)")
      ->type_name("A:B");
  app->add_option("--pitch-deg", pitch_text, "camera tilt-down range in degrees (default 20:45)")
      ->type_name("A:B");
  app->add_option("--tables", tables_text, "number of tables (default 1:3)")->type_name("A:B");
  app->add_option("--speed", speed_text, "robot speed in m/s (default 0.4)")->type_name("V");
  app->add_flag("--no-noise", no_noise, "exact depth (mm), no dropouts, no colour noise");
  app->add_flag("--multi-room", multi_room,
                "a multi-room apartment of the search bench (3-6 rooms, beds, sofas), one view "
                "of a piece of its furniture a frame, instead of one room along a path");
  app->add_option("--lcm-log", lcm_log,
                  "also write the frames as an LCM log of rgbd_frame_t on FINDMUG_RGBD (what "
                  "lcm-logplayer replays to findmugd), stamped with the sequence's frame times")
      ->type_name("FILE");
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  try {
    synth::SequenceSpec spec;
    spec.seed = parseSeed(seed_text);
    spec.frames = frames;
    spec.multi_room = multi_room;
    if (multi_room && (!tables_text.empty() || !speed_text.empty()))
      throw Error("flag --multi-room: --tables and --speed are for one room along a path "
                  "(a multi-room apartment is furnished by room kind, one view a frame)");
    if (!fps_text.empty()) spec.fps = findmug::tools::parseNumber("--fps", fps_text);
    if (!height_text.empty())
      std::tie(spec.path.height_min, spec.path.height_max) =
          parseRange("camera-height", height_text);
    if (!pitch_text.empty())
      std::tie(spec.path.pitch_min_deg, spec.path.pitch_max_deg) =
          parseRange("pitch-deg", pitch_text);
    if (!tables_text.empty()) {
      const auto [lo, hi] = parseRange("tables", tables_text);
      if (lo != static_cast<int>(lo) || hi != static_cast<int>(hi))
        throw Error("flag --tables: '" + tables_text + "' must be integers");
      spec.apartment.tables_min = static_cast<int>(lo);
      spec.apartment.tables_max = static_cast<int>(hi);
    }
    if (!speed_text.empty())
      spec.path.speed_mps = findmug::tools::parseNumber("--speed", speed_text);
    if (no_noise) {
      spec.render.noise.enabled = false;
      spec.render.noise.rgb_noise_sigma = 0.0;
    }

    tools::ProgressBar bar("findmug-synth");
    const auto truth =
        synth::writeSequence(out, spec, [&](int done, int total) { bar.update(done, total); });
    bar.finish();
    std::printf("wrote %d frames (%d table%s) to %s, ground truth in %s/ground_truth.yaml\n",
                spec.frames, static_cast<int>(truth.tables.size()),
                truth.tables.size() == 1 ? "" : "s", out.c_str(), out.c_str());
    if (!lcm_log.empty()) {
      writeLcmLog(out, truth, lcm_log);
      std::printf("wrote %d rgbd_frame_t messages on %s to %s\n", spec.frames,
                  std::string(io::kRgbdChannel).c_str(), lcm_log.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "findmug-synth: %s\n", e.what());
    return 1;
  }
}
