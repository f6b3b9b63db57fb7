// findmug-label-viewer — look at findmugd's labels without a GUI.
//
// Subscribes to FINDMUG_LABELS[_suffix] (label_image_t) and, when published,
// FINDMUG_RGBD[_suffix] (rgbd_frame_t). For each label image it prints one
// summary line (size, latency, share of each class, mean confidence) and
// writes a PNG overlay in the paper's palette (floor red, wall blue, ceiling
// orange, table green, chair pink, cabinet yellow, object purple, unknown
// brown, void black) blended with the colour frame of the same utime when
// one was received, or the plain palette image otherwise.
//
// Exits cleanly on SIGINT/SIGTERM, after --count label images, or at the end
// of a replayed log (--lcm-url file://LOG?speed=0). Bad messages are
// reported on stderr and skipped.
#include <array>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <utility>
#include <vector>

#include "client_common.hpp"
#include "findmug/error.hpp"
#include "findmug/image_io.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/label_image.hpp"
#include "findmug/labels.hpp"

namespace {

using namespace findmug;

constexpr const char* kProgram = "findmug-label-viewer";
// Colour frames kept for matching: labels arrive some frames after their input.
constexpr std::size_t kKeptColorFrames = 60;

const char* kUsage =
    "usage: findmug-label-viewer [options]\n"
    "  --lcm-url URL        LCM provider (default: LCM_DEFAULT_URL or udpm default);\n"
    "                       file://LOG?speed=0 replays a log and exits at its end\n"
    "  --channel-suffix S   listen on FINDMUG_LABELS_S (and FINDMUG_RGBD_S)\n"
    "  --out DIR            where overlays go (default: current directory)\n"
    "  --alpha A            label colour weight over the image, 0..1 (default 0.6)\n"
    "  --every K            write every K-th overlay (default 1)\n"
    "  --no-png             console summary only\n"
    "  --count N            exit after N label images\n"
    "  --help\n";

struct ColorFrame {
  std::uint64_t utime = 0;
  int width = 0, height = 0;
  std::vector<Rgb8> rgb;
};

class LabelViewer {
 public:
  LabelViewer(std::filesystem::path out_dir, float alpha, long every, bool write_png)
      : out_dir_(std::move(out_dir)), alpha_(alpha), every_(every), write_png_(write_png) {}

  void onFrame(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    try {
      RgbdFrame frame = io::decodeRgbdFrame(buffer->data, buffer->data_size, channel);
      colors_.push_back({frame.utime, frame.width, frame.height, std::move(frame.rgb)});
      while (colors_.size() > kKeptColorFrames) colors_.pop_front();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: skipping bad frame: %s\n", kProgram, e.what());
    }
  }

  void onLabels(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    ++received_;
    io::LabelImageMessage message;
    try {
      message = io::decodeLabelImage(buffer->data, buffer->data_size, channel);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: skipping bad label image: %s\n", kProgram, e.what());
      return;
    }
    const LabelImage& image = message.image;
    const std::size_t pixels = image.labels.size();
    std::array<std::size_t, kNumLabels + 1> counts{};  // last: void
    for (std::uint8_t id : image.labels) ++counts[id < kNumLabels ? id : kNumLabels];
    double confidence_sum = 0.0;
    std::size_t confident = 0;
    for (std::size_t i = 0; i < image.confidence.size(); ++i) {
      if (image.labels[i] != kVoidLabel) {
        confidence_sum += image.confidence[i];
        ++confident;
      }
    }

    std::string summary = "labels seq " + std::to_string(message.seq) + " utime " +
                          std::to_string(message.utime) + " " + std::to_string(image.width) + "x" +
                          std::to_string(image.height);
    char buf[96];
    std::snprintf(buf, sizeof(buf), " latency %.1f ms:", message.latency_us / 1000.0);
    summary += buf;
    for (int id = 0; id <= kNumLabels; ++id) {
      if (counts[id] == 0) continue;
      std::snprintf(buf, sizeof(buf), " %s %.1f%%",
                    id < kNumLabels ? std::string(kLabelNames[id]).c_str() : "void",
                    100.0 * static_cast<double>(counts[id]) / static_cast<double>(pixels));
      summary += buf;
    }
    if (confident > 0) {
      std::snprintf(buf, sizeof(buf), "; mean confidence %.2f", confidence_sum / confident);
      summary += buf;
    }

    if (write_png_ && (received_ - 1) % every_ == 0) {
      try {
        summary += "; " + writeOverlay(message);
      } catch (const std::exception& e) {
        summary += std::string("; overlay not written: ") + e.what();
      }
    }
    std::puts(summary.c_str());
    std::fflush(stdout);
  }

  long received() const { return received_; }

 private:
  std::string writeOverlay(const io::LabelImageMessage& message) const {
    const LabelImage& image = message.image;
    const ColorFrame* match = nullptr;
    for (const auto& c : colors_) {
      if (c.utime == message.utime && c.width == image.width && c.height == image.height) {
        match = &c;
      }
    }
    Image<Rgb8> overlay;
    overlay.width = image.width;
    overlay.height = image.height;
    if (match != nullptr) {
      overlay.pixels = colorizeLabels(image, match->rgb, alpha_);
    } else {
      // No colour frame for this utime (not published, or dropped): the palette alone.
      const std::vector<Rgb8> black(image.labels.size());
      overlay.pixels = colorizeLabels(image, black, 1.0f);
    }
    char name[64];
    std::snprintf(name, sizeof(name), "labels_%08lld.png", static_cast<long long>(message.seq));
    const std::filesystem::path path = out_dir_ / name;
    writePngRgb(path.string(), overlay);
    return std::string(match ? "overlay " : "palette (no colour frame) ") + path.string();
  }

  std::filesystem::path out_dir_;
  float alpha_;
  long every_;
  bool write_png_;
  long received_ = 0;
  std::deque<ColorFrame> colors_;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace findmug;
  std::string url, labels_channel, frames_channel;
  std::filesystem::path out_dir = ".";
  float alpha = 0.6f;
  long every = 1, count = 0;
  bool write_png = true;
  try {
    const clients::Flags flags(
        argc, argv, {"--lcm-url", "--channel-suffix", "--out", "--alpha", "--every", "--count"},
        {"--no-png", "--help"});
    if (flags.has("--help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    url = flags.get("--lcm-url", "");
    const std::string suffix = flags.get("--channel-suffix", "");
    labels_channel = io::channelName(io::kLabelsChannel, suffix);
    frames_channel = io::channelName(io::kRgbdChannel, suffix);
    out_dir = flags.get("--out", ".");
    alpha = static_cast<float>(flags.getDouble("--alpha", 0.6, 0.0, 1.0));
    every = flags.getInt("--every", 1, 1);
    count = flags.getInt("--count", 0, 1);
    write_png = !flags.has("--no-png");
    if (write_png && !std::filesystem::is_directory(out_dir)) {
      throw std::invalid_argument("--out " + out_dir.string() + ": not a directory");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n%s", kProgram, e.what(), kUsage);
    return 2;
  }

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "%s: cannot open LCM provider '%s'\n", kProgram,
                 url.empty() ? "default" : url.c_str());
    return 1;
  }
  clients::installStopHandlers();
  LabelViewer viewer(out_dir, alpha, every, write_png);
  lcm.subscribe(labels_channel, &LabelViewer::onLabels, &viewer);
  lcm.subscribe(frames_channel, &LabelViewer::onFrame, &viewer);
  std::fprintf(stderr, "%s: listening on %s and %s\n", kProgram, labels_channel.c_str(),
               frames_channel.c_str());
  return clients::receiveLoop(lcm, url, kProgram,
                              [&] { return count > 0 && viewer.received() >= count; });
}
