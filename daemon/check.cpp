#include "findmug/daemon/check.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/daemon/daemon.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::daemon {
namespace {

std::string format(const char* pattern, double a, double b = 0.0, double c = 0.0) {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), pattern, a, b, c);
  return buffer;
}

}  // namespace

std::string verdictLine(Verdict verdict, const std::string& item, const std::string& what,
                        const std::string& todo) {
  static const char* const tags[] = {"[ OK ]", "[WARN]", "[FAIL]", "[SKIP]"};
  std::string line = std::string(tags[static_cast<int>(verdict)]) + " " + item;
  line.resize(std::max<std::size_t>(line.size(), 16), ' ');
  line += what + "\n";
  if (!todo.empty() && (verdict == Verdict::Warn || verdict == Verdict::Fail)) {
    line += "       do: " + todo + "\n";
  }
  return line;
}

namespace {

// The self-check's steps, in the order a robot's start-up needs them; each says its
// verdict line and returns what the next step needs (nothing when it failed).
class SelfCheck {
 public:
  SelfCheck(const LoadedConfig& loaded, std::ostream& out)
      : loaded_(loaded), d_(loaded.daemon), check_(d_.check), out_(out) {}

  int failures() const { return failures_; }

  void say(Verdict v, const std::string& item, const std::string& what,
           const std::string& todo = "") {
    if (v == Verdict::Fail) ++failures_;
    out_ << verdictLine(v, item, what, todo) << std::flush;
  }

  void config() {
    say(Verdict::Ok, "config",
        loaded_.origin + ": valid (source " + d_.source + ", output " +
            (effectiveLcmUrl(d_).empty() ? "LCM default" : effectiveLcmUrl(d_)) + ")");
  }

  // The model loads, and the config gives none of the settings it records another value.
  std::unique_ptr<Segmenter> model() {
    try {
      std::string model_id;
      auto forest = loadModel(d_.model_path, &model_id);
      auto segmenter = std::make_unique<Segmenter>(loaded_.config.segmenter, forest);
      say(Verdict::Ok, "model",
          d_.model_path + ": " + forest->summary() + " (" + model_id +
              "), the settings it records in force");
      return segmenter;
    } catch (const std::exception& e) {
      say(Verdict::Fail, "model", e.what(),
          "set daemon.model_path to a model made by findmug-train (the package's are in "
          "/usr/share/findmug/models), and leave out of the config the settings it records "
          "(findmugd --help-settings marks them [model]) or give them its values");
      return nullptr;
    }
  }

  // The source opens as the daemon would open it.
  std::unique_ptr<io::FrameSource> source() {
    try {
      io::SourceSpec spec = io::parseSourceSpec(d_.source);
      if (spec.kind == "lcm" && spec.options.lcm_url.empty())
        spec.options.lcm_url = effectiveLcmUrl(d_);
      auto source = io::makeSource(spec);
      say(Verdict::Ok, "source", source->describe());
      return source;
    } catch (const std::exception& e) {
      say(Verdict::Fail, "source", std::string("daemon.source '") + d_.source + "': " + e.what(),
          "fix daemon.source (openni2, openni2:/file.oni, lcm:CHANNEL, dataset:/dir, pcd:/dir, "
          "...)");
      say(Verdict::Skipped, "frames", "no source");
      say(Verdict::Skipped, "ground", "no frames");
      return nullptr;
    }
  }

  // Up to check.frames within check.timeout_s, and what they are like.
  std::vector<RgbdFrame> frames(io::FrameSource& source) {
    io::SourceState state_before_stop = io::SourceState::Starting;
    std::vector<RgbdFrame> frames = readFrames(source, state_before_stop);
    const io::SourceStats stats = source.stats();
    if (frames.empty()) {
      say(Verdict::Fail, "frames",
          format("none within %.0f s", check_.timeout_s) + " (source " +
              std::string(io::sourceStateName(state_before_stop)) +
              (stats.last_error.empty() ? "" : ", last error: " + stats.last_error) + ")",
          "plug in the camera and check that the service user may open it (groups video, "
          "plugdev; `lsusb`), or that something publishes on the LCM channel");
      say(Verdict::Skipped, "ground", "no frames");
      say(Verdict::Skipped, "labels", "no frames");
      return frames;
    }
    const RgbdFrame& first = frames.front();
    double rate = 0.0;
    if (frames.size() >= 2 && frames.back().utime > first.utime) {
      rate = (frames.size() - 1) * 1e6 / static_cast<double>(frames.back().utime - first.utime);
    }
    double valid_sum = 0.0;
    for (const auto& f : frames) {
      const auto valid = std::count_if(f.depth_mm.begin(), f.depth_mm.end(),
                                       [](std::uint16_t v) { return v != 0; });
      valid_sum += static_cast<double>(valid) / static_cast<double>(f.depth_mm.size());
    }
    const double valid_share = valid_sum / static_cast<double>(frames.size());
    const std::string frame_text =
        std::to_string(frames.size()) + " frames, " + std::to_string(first.width) + "x" +
        std::to_string(first.height) +
        (rate > 0 ? format(", %.1f fps", rate) : std::string(", frame rate not measurable")) +
        format(", depth valid on %.0f%% of pixels", 100.0 * valid_share) +
        (stats.frames_rejected ? ", " + std::to_string(stats.frames_rejected) + " rejected" : "");
    if (valid_share < check_.min_valid_depth) {
      say(Verdict::Warn, "frames", frame_text,
          format("less than %.0f%% valid depth: look for a covered or dirty IR projector, "
                 "strong sunlight, or surfaces closer than the sensor's minimum range",
                 100.0 * check_.min_valid_depth));
    } else {
      say(Verdict::Ok, "frames", frame_text);
    }
    return frames;
  }

  // The daemon labels only frames in which it finds the floor: the first such frame, or
  // nullptr.
  const RgbdFrame* ground(const Segmenter& segmenter, const std::vector<RgbdFrame>& frames) {
    int with_ground = 0;
    std::optional<GroundPlane> example;
    const RgbdFrame* example_frame = nullptr;
    for (const auto& f : frames) {
      try {
        PreparedFrame prepared = segmenter.prepare(f);
        if (prepared.ground) {
          ++with_ground;
          if (!example) {
            example = prepared.ground;
            example_frame = &f;
          }
        }
      } catch (const std::exception&) {
        // counted as no ground
      }
    }
    if (with_ground == 0) {
      say(Verdict::Fail, "ground",
          "no floor plane found in any of " + std::to_string(frames.size()) + " frames",
          "point the camera so that a good part of the floor is in view, at least "
          "segmenter ground.min_camera_height_m above it, or publish frames that carry the "
          "camera mount (rgbd_frame_t extrinsics)");
      say(Verdict::Skipped, "labels", "no frame with a floor");
      return nullptr;
    }
    const Eigen::Vector3f up = example->normal_camera.normalized();
    const double tilt_deg = std::acos(std::clamp(-up.y(), -1.0f, 1.0f)) * 180.0 / M_PI;
    say(with_ground == static_cast<int>(frames.size()) ? Verdict::Ok : Verdict::Warn, "ground",
        "floor found in " + std::to_string(with_ground) + " of " + std::to_string(frames.size()) +
            " frames" +
            format(" (camera %.2f m above it, tilted %.0f deg)", example->offset, tilt_deg),
        "frames without a floor are not labelled: keep more floor in view");
    return example_frame;
  }

  // One frame through the whole segmentation: how long, and the labels' shares.
  void labels(const Segmenter& segmenter, const RgbdFrame& frame) {
    try {
      const auto t0 = std::chrono::steady_clock::now();
      const LabelledFrame labelled = segmenter.process(frame);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      std::array<std::size_t, kNumLabels> counts{};
      std::size_t labelled_pixels = 0;
      for (std::uint8_t id : labelled.labels.labels) {
        if (id < kNumLabels) ++counts[id], ++labelled_pixels;
      }
      std::string shares;
      for (int id = 0; id < kNumLabels; ++id) {
        if (labelled_pixels == 0 || counts[id] * 20 < labelled_pixels) continue;  // >= 5 %
        // (appended piecewise: GCC 12 warns falsely on " " + std::string(...))
        shares += ' ';
        shares += kLabelNames[id];
        shares += format(" %.0f%%", 100.0 * static_cast<double>(counts[id]) / labelled_pixels);
      }
      say(Verdict::Ok, "labels", format("one frame labelled in %.0f ms:", ms) + shares);
    } catch (const std::exception& e) {
      say(Verdict::Fail, "labels", std::string("segmentation failed: ") + e.what(),
          "report this with the frame (findmug-grab can record it)");
    }
  }

 private:
  // next() blocks (a camera that is not there keeps reconnecting), so it runs on its own
  // thread and stop() ends it.
  std::vector<RgbdFrame> readFrames(io::FrameSource& source, io::SourceState& state_before_stop) {
    std::vector<RgbdFrame> frames;
    const auto started = std::chrono::steady_clock::now();
    std::thread reader([&] {
      while (static_cast<int>(frames.size()) < check_.frames) {
        auto frame = source.next();
        if (!frame) break;
        frames.push_back(std::move(*frame));
      }
    });
    const auto deadline = started + std::chrono::duration<double>(check_.timeout_s);
    while (std::chrono::steady_clock::now() < deadline) {
      const io::SourceState state = source.state();
      if (state == io::SourceState::EndOfStream || state == io::SourceState::Failed ||
          state == io::SourceState::Stopped) {
        break;
      }
      // `frames` is only read after join(); progress is checked through the source's stats.
      if (source.stats().frames_delivered >= static_cast<std::uint64_t>(check_.frames)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    state_before_stop = source.state();
    source.stop();
    reader.join();
    return frames;
  }

  const LoadedConfig& loaded_;
  const DaemonConfig& d_;
  const CheckConfig& check_;
  std::ostream& out_;
  int failures_ = 0;
};

}  // namespace

int runSelfCheck(const LoadedConfig& loaded, std::ostream& out) {
  SelfCheck check(loaded, out);
  check.config();
  const std::unique_ptr<Segmenter> segmenter = check.model();
  const std::unique_ptr<io::FrameSource> source = check.source();
  if (!source) return check.failures();
  const std::vector<RgbdFrame> frames = check.frames(*source);
  if (frames.empty()) return check.failures();
  if (!segmenter) {
    check.say(Verdict::Skipped, "ground",
              "no model (the ground search uses the segmenter's settings)");
    return check.failures();
  }
  const RgbdFrame* with_floor = check.ground(*segmenter, frames);
  if (with_floor) check.labels(*segmenter, *with_floor);
  return check.failures();
}

}  // namespace findmug::daemon
