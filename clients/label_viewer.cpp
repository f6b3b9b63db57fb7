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
// Pictures for people: every overlay has a legend panel; when FINDMUG_TABLES[_suffix]
// brings the tables of the same frame, the table hulls and the search positions (numbered
// in visiting order, unreachable ones crossed) are drawn over the image with the camera
// the daemon used for the frame (label_image_t.camera_to_base: every source, replays,
// datasets and PCD included), or, from an older daemon, the colour frame's mount; with them
// the object candidates of FINDMUG_OBJECTS[_suffix] on those tables (a marker in each
// candidate's mean colour at its centroid, with its id). A label
// image that carries the frame's colour image (findmugd daemon.publish_color) is drawn
// over it when FINDMUG_RGBD is not published. table_map.png and table_map.svg
// show the tables top-down: the table map with the robot's pose from
// FINDMUG_TABLE_MAP[_suffix], or, until a map arrives, the latest frame's tables around
// the robot. When findmugd publishes its fused semantic map (daemon.semantic_map),
// semantic_map.png shows FINDMUG_SEMANTIC_MAP[_suffix] top-down: each floor cell in the
// colour of the label on top there, faded by how sure the map is, with the tables of
// FINDMUG_TABLE_MAP (ids, supporting frames and viewpoints) and the robot's pose
// (semantic_map_picture.hpp). --source SPEC takes the colour frames from a frame source (e.g. the
// dataset folder the daemon replayed), matched by sequence number, for logs without frames.
//
// Exits cleanly on SIGINT/SIGTERM, after --count label images, or at the end
// of a replayed log (--lcm-url file://LOG?speed=0). Bad messages are
// reported on stderr and skipped.
#include <array>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "client_common.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/io/subscriber.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug_cli.hpp"
#include "picture.hpp"
#include "semantic_map_picture.hpp"

namespace {

using namespace findmug;

constexpr const char* kProgram = "findmug-label-viewer";
// Colour frames kept for matching: labels arrive some frames after their input.
constexpr std::size_t kKeptColorFrames = 60;

struct ColorFrame {
  std::uint64_t utime = 0;
  std::int64_t seq = 0;
  int width = 0, height = 0;
  std::vector<Rgb8> rgb;
  std::vector<std::uint16_t> depth_mm;  // to tell search positions hidden behind surfaces
  CameraIntrinsics intrinsics;
  std::optional<CameraExtrinsics> extrinsics;
};
// Label images kept for tables that arrive after them.
constexpr std::size_t kKeptLabelImages = 8;

class LabelViewer {
 public:
  LabelViewer(std::filesystem::path out_dir, float alpha, long every, bool write_png,
              std::unique_ptr<io::FrameSource> source)
      : out_dir_(std::move(out_dir)),
        alpha_(alpha),
        every_(every),
        write_png_(write_png),
        source_(std::move(source)) {}

  // Decoded messages, from the subscribers (bad ones are reported there).
  void onFrame(const RgbdFrame& frame) { keep(frame); }

  void onTables(const io::TablesMessage& message) {
    const bool is_map = message.content == io::TablesContent::Map;
    if (write_png_ && (is_map || !have_map_)) {
      have_map_ = have_map_ || is_map;
      writeTableMap(message);
    }
    if (is_map) {
      table_map_ = message;
      if (semantic_map_) writeSemanticMap();
      return;
    }
    tables_.push_back(message);
    while (tables_.size() > kKeptLabelImages) tables_.pop_front();
    // Labels of this frame already written: draw them again, now with the tables.
    for (const auto& labels : labels_) {
      if (labels.utime == message.utime && write_png_) {
        try {
          const std::string written = writeOverlay(labels);
          std::printf("tables seq %lld: %zu tables; redrawn %s\n",
                      static_cast<long long>(message.seq), message.tables.size(), written.c_str());
          std::fflush(stdout);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "%s: overlay not redrawn: %s\n", kProgram, e.what());
        }
      }
    }
  }

  // The candidates of a frame, which arrive after its tables: its overlay is drawn again.
  void onObjects(const io::ObjectsMessage& message) {
    objects_.push_back(message);
    while (objects_.size() > kKeptLabelImages) objects_.pop_front();
    for (const auto& labels : labels_) {
      if (labels.utime != message.utime || !write_png_) continue;
      try {
        const std::string written = writeOverlay(labels);
        std::printf("objects seq %lld: %zu objects; redrawn %s\n",
                    static_cast<long long>(message.seq), message.objects.size(), written.c_str());
        std::fflush(stdout);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: overlay not redrawn: %s\n", kProgram, e.what());
      }
    }
  }

  void onSemanticMap(const io::SemanticMapMessage& message) {
    semantic_map_ = message;
    std::printf("semantic map seq %lld: %zu voxels, %lld frames\n",
                static_cast<long long>(message.seq), message.voxels.size(),
                static_cast<long long>(message.frames));
    std::fflush(stdout);
    if (write_png_) writeSemanticMap();
  }

  // A bad label image counts as received (for --count and --every) and is skipped.
  void onBadLabels(const std::string& what) {
    ++received_;
    std::fprintf(stderr, "%s: skipping bad label image: %s\n", kProgram, what.c_str());
  }

  void onLabels(const io::LabelImageMessage& message) {
    ++received_;
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
      labels_.push_back(message);
      while (labels_.size() > kKeptLabelImages) labels_.pop_front();
    }
    std::puts(summary.c_str());
    std::fflush(stdout);
  }

  long received() const { return received_; }

 private:
  void keep(RgbdFrame frame) {
    colors_.push_back({frame.utime, frame.seq, frame.width, frame.height, std::move(frame.rgb),
                       std::move(frame.depth_mm), frame.intrinsics, frame.extrinsics});
    while (colors_.size() > kKeptColorFrames) colors_.pop_front();
  }

  // The colour frame of a label image: same utime from FINDMUG_RGBD, or the same
  // sequence number from --source (read ahead as far as needed).
  const ColorFrame* colourFor(const io::LabelImageMessage& message) {
    const LabelImage& image = message.image;
    auto find = [&]() -> const ColorFrame* {
      for (const auto& c : colors_) {
        const bool same = source_ ? c.seq == message.seq : c.utime == message.utime;
        if (same && c.width == image.width && c.height == image.height) return &c;
      }
      return nullptr;
    };
    if (source_) {
      while (!find() && (colors_.empty() || colors_.back().seq < message.seq)) {
        auto frame = source_->next();
        if (!frame) break;
        keep(std::move(*frame));
      }
    }
    return find();
  }

  std::string writeOverlay(const io::LabelImageMessage& message) {
    const LabelImage& image = message.image;
    const ColorFrame* match = colourFor(message);
    Image<Rgb8> overlay;
    overlay.width = image.width;
    overlay.height = image.height;
    // The daemon's own colour image (daemon.publish_color) when no frame matched.
    std::vector<Rgb8> carried;
    if (match == nullptr) carried = io::decodeLabelImageColor(message, "FINDMUG_LABELS");
    if (match != nullptr) {
      overlay.pixels = colorizeLabels(image, match->rgb, alpha_);
    } else if (!carried.empty()) {
      overlay.pixels = colorizeLabels(image, carried, alpha_);
    } else {
      // No colour frame for this utime (not published, or dropped): the palette alone.
      const std::vector<Rgb8> black(image.labels.size());
      overlay.pixels = colorizeLabels(image, black, 1.0f);
    }
    std::string tables_note;
    for (const auto& tables : tables_) {
      if (tables.utime != message.utime) continue;
      // The camera as the daemon used it for this frame (every source), else the mount
      // the colour frame carried (older daemons).
      const bool frame_mount = match != nullptr && match->extrinsics.has_value();
      if (!message.camera && !frame_mount) {
        if (!tables.tables.empty()) {
          tables_note = " (" + std::to_string(tables.tables.size()) +
                        " tables not drawn: the daemon found no floor for this frame)";
        }
        break;
      }
      clients::Canvas canvas(std::move(overlay));
      const std::vector<std::uint16_t>* depth = match ? &match->depth_mm : nullptr;
      const int drawn = message.camera
                            ? clients::drawTablesInImage(canvas, tables, message.camera->intrinsics,
                                                         message.camera->camera_to_base, depth)
                            : clients::drawTablesInImage(canvas, tables, match->intrinsics,
                                                         *match->extrinsics, depth);
      tables_note = " with " + std::to_string(drawn) + " of " +
                    std::to_string(tables.tables.size()) + " tables in view";
      tables_note += drawObjects(canvas, message, match);
      overlay = canvas.image();
      break;
    }
    char name[64];
    std::snprintf(name, sizeof(name), "labels_%08lld.png", static_cast<long long>(message.seq));
    const std::filesystem::path path = out_dir_ / name;
    writePngRgb(path.string(), clients::withLegend(overlay));
    return std::string(match || !carried.empty() ? "overlay " : "palette (no colour frame) ") +
           path.string() +
           tables_note;
  }

  // The candidates of the label image's frame, with the camera its tables were drawn with;
  // returns the note for the summary ("" when none arrived for this frame).
  std::string drawObjects(clients::Canvas& canvas, const io::LabelImageMessage& message,
                          const ColorFrame* match) const {
    for (const auto& objects : objects_) {
      if (objects.utime != message.utime) continue;
      const int drawn =
          message.camera
              ? clients::drawObjectsInImage(canvas, objects, message.camera->intrinsics,
                                            message.camera->camera_to_base)
              : clients::drawObjectsInImage(canvas, objects, match->intrinsics, *match->extrinsics);
      return ", " + std::to_string(drawn) + " of " + std::to_string(objects.objects.size()) +
             " objects";
    }
    return "";
  }

  void writeTableMap(const io::TablesMessage& message) const {
    try {
      writePngRgb((out_dir_ / "table_map.png").string(), clients::tableMapPng(message));
      std::ofstream svg(out_dir_ / "table_map.svg");
      svg << clients::tableMapSvg(message);
      if (!svg) throw Error((out_dir_ / "table_map.svg").string() + ": cannot write");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: table map not written: %s\n", kProgram, e.what());
    }
  }

  void writeSemanticMap() const {
    try {
      writePngRgb((out_dir_ / "semantic_map.png").string(),
                  clients::semanticMapPng(*semantic_map_, table_map_ ? &*table_map_ : nullptr));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: semantic map not written: %s\n", kProgram, e.what());
    }
  }

  std::filesystem::path out_dir_;
  float alpha_;
  long every_;
  bool write_png_;
  std::unique_ptr<io::FrameSource> source_;  // colour frames by seq (--source), or null
  long received_ = 0;
  bool have_map_ = false;  // a FINDMUG_TABLE_MAP message arrived: table_map.* shows the map
  std::optional<io::TablesMessage> table_map_;            // the latest FINDMUG_TABLE_MAP
  std::optional<io::SemanticMapMessage> semantic_map_;  // the latest FINDMUG_SEMANTIC_MAP
  std::deque<ColorFrame> colors_;
  std::deque<io::LabelImageMessage> labels_;
  std::deque<io::TablesMessage> tables_;
  std::deque<io::ObjectsMessage> objects_;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace findmug;
  std::string url, suffix, out_text = ".", source_spec;
  double alpha = 0.6;
  long every = 1, count = 0;
  bool no_png = false;
  auto app = cli::makeApp(kProgram,
                          "Prints a summary of each label image findmugd publishes and writes "
                          "overlays with a legend, tables and search positions, and a top-down "
                          "table map (table_map.png, table_map.svg) and, when published, the "
                          "semantic map (semantic_map.png)");
  cli::addLcmUrlFlag(*app, url,
                     "LCM provider (default: LCM_DEFAULT_URL or udpm default); "
                     "file://LOG?speed=0 replays a log and exits at its end");
  cli::addChannelSuffixFlag(*app, suffix);
  app->add_option("--out", out_text, "where overlays and the table map go")
      ->type_name("DIR")
      ->capture_default_str();
  app->add_option("--alpha", alpha, "label colour weight over the image")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app->add_option("--every", every, "write every K-th overlay")
      ->check(cli::positive())
      ->capture_default_str();
  app->add_flag("--no-png", no_png, "console summary only");
  app->add_option("--count", count, "exit after N label images")->check(cli::positive());
  cli::addSourceFlag(*app, source_spec,
                     "colour frames (and camera mount) from this frame source, matched by "
                     "sequence number, e.g. the dataset:DIR the daemon replayed");
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  const std::filesystem::path out_dir = out_text;
  const bool write_png = !no_png;
  if (write_png && !std::filesystem::is_directory(out_dir)) {
    std::fprintf(stderr, "%s: --out %s: not a directory (see --help)\n", kProgram,
                 out_dir.string().c_str());
    return 2;
  }
  const std::string labels_channel(io::kLabelsChannel), frames_channel(io::kRgbdChannel),
      tables_channel(io::kTablesChannel), map_channel(io::kTableMapChannel),
      semantic_channel(io::kSemanticMapChannel), objects_channel(io::kObjectsChannel);
  try {
    io::checkChannelSuffix(suffix);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: --channel-suffix: %s (see --help)\n", kProgram, e.what());
    return 2;
  }
  std::unique_ptr<io::FrameSource> source;
  if (!source_spec.empty()) {
    try {
      source = io::makeSource(source_spec);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: --source: %s\n", kProgram, e.what());
      return 2;
    }
  }

  const std::shared_ptr<io::Bus> bus = clients::openBus(url, kProgram, suffix);
  if (!bus) return 1;
  clients::installStopHandlers();
  LabelViewer viewer(out_dir, static_cast<float>(alpha), every, write_png, std::move(source));
  // This thread owns the bus: the subscribers' callbacks run inside receiveLoop.
  auto report = [](const char* what) {
    return [what](const std::string& error) {
      std::fprintf(stderr, "%s: skipping bad %s: %s\n", kProgram, what, error.c_str());
    };
  };
  auto decode_tables = [](const std::uint8_t* d, std::size_t n, const std::string& c) {
    return io::decodeTables(d, n, c);
  };
  io::Subscriber<io::LabelImageMessage> labels(
      *bus, labels_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeLabelImage(d, n, c);
      },
      [&](const io::LabelImageMessage& m, const std::string&) { viewer.onLabels(m); },
      [&](const std::string& error) { viewer.onBadLabels(error); });
  io::Subscriber<RgbdFrame> frames(
      *bus, frames_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeRgbdFrame(d, n, c);
      },
      [&](const RgbdFrame& f, const std::string&) { viewer.onFrame(f); }, report("frame"));
  io::Subscriber<io::TablesMessage> tables(
      *bus, tables_channel, decode_tables,
      [&](const io::TablesMessage& m, const std::string&) { viewer.onTables(m); },
      report("tables message"));
  io::Subscriber<io::TablesMessage> table_map(
      *bus, map_channel, decode_tables,
      [&](const io::TablesMessage& m, const std::string&) { viewer.onTables(m); },
      report("tables message"));
  io::Subscriber<io::ObjectsMessage> objects(
      *bus, objects_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeObjects(d, n, c);
      },
      [&](const io::ObjectsMessage& m, const std::string&) { viewer.onObjects(m); },
      report("objects message"));
  io::Subscriber<io::SemanticMapMessage> semantic_map(
      *bus, semantic_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeSemanticMap(d, n, c);
      },
      [&](const io::SemanticMapMessage& m, const std::string&) { viewer.onSemanticMap(m); },
      report("semantic map"));
  std::fprintf(stderr, "%s: listening on %s, %s, %s, %s, %s and %s, %s\n", kProgram,
               labels_channel.c_str(), frames_channel.c_str(), tables_channel.c_str(),
               objects_channel.c_str(), map_channel.c_str(), semantic_channel.c_str(),
               bus->describe().c_str());
  return clients::receiveLoop(*bus, kProgram,
                              [&] { return count > 0 && viewer.received() >= count; });
}
