// Saving frames worth labelling; see frame_collector.hpp.
#include "findmug/daemon/frame_collector.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/common/numbers.hpp"

namespace findmug::daemon {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFramesHeader =
    "frame,scene,utime,trigger,mean_confidence,tables,model_id,note";

std::string number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot read");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Through a temporary file in the same folder and a rename: a crash leaves the
// old file or the new one, never half of one.
void writeAtomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw Error(tmp.string() + ": cannot write");
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw Error(path.string() + ": cannot replace (" + ec.message() + ")");
}

// Appends `row` to the CSV at `path`, writing `header` first when it is new.
void appendRow(const fs::path& path, const std::string& header, const std::string& row) {
  std::string text = fs::exists(path) ? readText(path) : header + "\n";
  if (!text.empty() && text.back() != '\n') text += '\n';
  writeAtomically(path, text + row + "\n");
}

// "fx: 1" lines of an intrinsics.yaml (the layout writeLabeledFrame writes).
CameraIntrinsics readIntrinsics(const fs::path& path) {
  std::istringstream in(readText(path));
  std::map<std::string, double> values;
  for (std::string line; std::getline(in, line);) {
    const auto colon = line.find(':');
    if (line.empty() || line[0] == '#' || colon == std::string::npos) continue;
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(' '));
    const auto parsed = parseNumber(value);
    if (!parsed) throw Error(path.string() + ": '" + line + "' is not KEY: NUMBER");
    values[line.substr(0, colon)] = *parsed;
  }
  for (const char* key : {"fx", "fy", "cx", "cy"}) {
    if (!values.count(key)) throw Error(path.string() + ": no " + key);
  }
  return {values["fx"], values["fy"], values["cx"], values["cy"]};
}

bool sameCamera(const CameraIntrinsics& a, const CameraIntrinsics& b) {
  const auto same = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::abs(y); };
  return same(a.fx, b.fx) && same(a.fy, b.fy) && same(a.cx, b.cx) && same(a.cy, b.cy);
}

}  // namespace

FrameCollector::Options FrameCollector::fromConfig(const DaemonConfig& config) {
  Options o;
  o.dir = config.collect_dir;
  o.max_frames = static_cast<std::uint64_t>(config.collect_max_frames);
  o.max_bytes = static_cast<std::uint64_t>(std::llround(config.collect_max_mb * 1024 * 1024));
  o.min_interval_s = config.collect_min_interval_s;
  o.low_confidence = config.collect_low_confidence;
  o.flicker_changes = config.collect_flicker_changes;
  o.flicker_window_s = config.collect_flicker_window_s;
  o.queue_capacity = static_cast<std::size_t>(config.collect_queue);
  const auto now = std::chrono::duration_cast<std::chrono::seconds>(
                       std::chrono::system_clock::now().time_since_epoch())
                       .count();
  o.scene = "run" + std::to_string(now);
  return o;
}

FrameCollector::FrameCollector(Options options, std::function<std::string()> model_id,
                               OnError on_error)
    : options_(std::move(options)), model_id_(std::move(model_id)), on_error_(std::move(on_error)) {
  const fs::path root(options_.dir);
  std::error_code ec;
  for (const char* sub : {"rgb", "depth", ".tmp"}) {
    fs::create_directories(root / sub, ec);
    if (ec) {
      throw Error("daemon.collect_dir: " + (root / sub).string() + ": cannot create (" +
                  ec.message() + ")");
    }
  }
  // What the folder already holds counts against the bound.
  for (const char* sub : {"rgb", "depth"}) {
    for (const auto& entry : fs::directory_iterator(root / sub, ec)) {
      if (!entry.is_regular_file() || entry.path().extension() != ".png") continue;
      bytes_ += entry.file_size();
      if (std::string(sub) == "rgb") ++frames_;
    }
  }
  spdlog::info("collecting frames worth labelling into {} ({} frames, {:.1f} MB there; bound {} "
               "frames, {:.0f} MB)",
               options_.dir, frames_, static_cast<double>(bytes_) / (1 << 20), options_.max_frames,
               static_cast<double>(options_.max_bytes) / (1 << 20));
  StageOptions stage;
  stage.name = "collect";
  stage.queue_capacity = std::max<std::size_t>(1, options_.queue_capacity);
  stage.thread_name = "findmug-collect";
  writer_ = std::make_unique<Stage<Job, Written>>(
      std::move(stage),
      StageCallbacks<Job, Written>{
          .work = [this](Job& job) -> std::optional<Written> { return writeJob(job); },
          .emit = [this](Written&& written) { recordWritten(std::move(written)); },
          .on_error = on_error_,
      });
  writer_->start();
}

FrameCollector::~FrameCollector() { stop(); }

void FrameCollector::stop() { writer_->stop(StopMode::Drain); }

FrameCollector::Counters FrameCollector::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

void FrameCollector::requestSave(std::int64_t request_id, const std::string& note) {
  for (const char c : note) {
    const auto u = static_cast<unsigned char>(c);
    if (c == ',' || c == '"' || u < 0x20 || u == 0x7f) {
      throw Error("save_frame: the note (frames.csv) may not hold a comma, a quote or a control "
                  "character");
    }
  }
  std::lock_guard lock(mutex_);
  requests_.emplace_back(request_id, note);
}

std::optional<double> FrameCollector::meanConfidence(const LabelImage& labels) {
  if (labels.confidence.size() != labels.labels.size()) return std::nullopt;
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < labels.labels.size(); ++i) {
    if (labels.labels[i] == kVoidLabel || labels.confidence[i] <= 0.0f) continue;
    sum += labels.confidence[i];
    ++n;
  }
  if (n == 0) return std::nullopt;
  return sum / static_cast<double>(n);
}

std::optional<std::string> FrameCollector::automaticTrigger(const LabelledFrame& labelled) {
  const RgbdFrame& frame = labelled.segmented.prepared.frame;
  std::optional<std::string> trigger;
  if (options_.flicker_changes > 0) {
    const std::size_t count = labelled.tables.size();
    if (last_table_count_ && *last_table_count_ != count) table_changes_.push_back(frame.utime);
    last_table_count_ = count;
    const auto window_us = static_cast<std::uint64_t>(std::llround(options_.flicker_window_s * 1e6));
    while (!table_changes_.empty() && frame.utime > table_changes_.front() + window_us) {
      table_changes_.pop_front();
    }
    if (table_changes_.size() >= static_cast<std::size_t>(options_.flicker_changes)) {
      trigger = "table_flicker";
      table_changes_.clear();  // the next trigger needs as many changes again
    }
  }
  if (!trigger && options_.low_confidence > 0.0) {
    const auto mean = meanConfidence(labelled.labels);
    if (mean && *mean < options_.low_confidence) trigger = "low_confidence";
  }
  if (!trigger) return std::nullopt;
  const auto interval_us = static_cast<std::uint64_t>(std::llround(options_.min_interval_s * 1e6));
  if (last_automatic_utime_ && frame.utime < *last_automatic_utime_ + interval_us) {
    spdlog::debug("collect: {} of {} within daemon.collect_min_interval_s of the last save",
                  *trigger, frameName(frame));
    return std::nullopt;
  }
  last_automatic_utime_ = frame.utime;
  return trigger;
}

void FrameCollector::consume(FrameResult& result) {
  const LabelledFrame& labelled = result.labelled;
  std::optional<std::pair<std::int64_t, std::string>> request;
  {
    std::lock_guard lock(mutex_);
    if (!requests_.empty()) {
      request = std::move(requests_.front());
      requests_.pop_front();
    }
  }
  // The triggers see every frame (the flicker window), asked for or not.
  const std::optional<std::string> automatic = automaticTrigger(labelled);
  if (request) {
    enqueue(labelled, "request " + std::to_string(request->first), request->second,
            meanConfidence(labelled.labels));
  } else if (automatic) {
    enqueue(labelled, *automatic, "", meanConfidence(labelled.labels));
  }
}

void FrameCollector::refuse(const std::string& what) {
  {
    std::lock_guard lock(mutex_);
    ++counters_.refused;
  }
  if (on_error_) on_error_("collect: " + what);
}

void FrameCollector::enqueue(const LabelledFrame& labelled, const std::string& trigger,
                             const std::string& note, std::optional<double> confidence) {
  const RgbdFrame& frame = labelled.segmented.prepared.frame;
  const std::string name = std::to_string(frame.utime) + "_" + std::to_string(frame.seq);
  std::string why;
  {
    std::lock_guard lock(mutex_);
    // queued_ counts the frame being written too, so the writer's queue has room for the
    // push below, which therefore never evicts a frame (only this thread pushes).
    if (frames_ + queued_ >= options_.max_frames) {
      why = "daemon.collect_max_frames (" + std::to_string(options_.max_frames) + ") reached";
    } else if (bytes_ >= options_.max_bytes) {
      why = "daemon.collect_max_mb reached (" + std::to_string(bytes_) + " bytes)";
    } else if (queued_ >= options_.queue_capacity) {
      why = "the writer is still busy with " + std::to_string(queued_) +
            " frames (daemon.collect_queue)";
    } else {
      ++queued_;
    }
  }
  if (why.empty()) {
    Job job;
    job.name = name;
    job.frame.width = frame.width;
    job.frame.height = frame.height;
    job.frame.rgb = frame.rgb;
    job.frame.depth_mm = frame.depth_mm;
    job.frame.intrinsics = frame.intrinsics;
    job.frame.extrinsics = frame.extrinsics;
    job.frame.gravity_up = frame.gravity_up;
    job.frame.utime = frame.utime;
    job.frame.seq = frame.seq;
    job.row = options_.scene + "," + std::to_string(frame.utime) + "," + trigger + "," +
              (confidence ? number(*confidence) : std::string()) + "," +
              std::to_string(labelled.tables.size()) + "," + model_id_() + "," + note;
    if (writer_->push(std::move(job))) return;
    std::lock_guard lock(mutex_);
    --queued_;
    why = "the collector is stopped";
  }
  refuse("not saving " + frameName(frame) + " (" + trigger + "): " + why);
}

FrameCollector::Written FrameCollector::writeJob(const Job& job) {
  Written written{job.name, 0, ""};
  try {
    write(job);
    const fs::path root(options_.dir);
    written.bytes = fs::file_size(root / "rgb" / (job.name + ".png")) +
                    fs::file_size(root / "depth" / (job.name + ".png"));
  } catch (const std::exception& e) {
    written.error = e.what();
  }
  return written;
}

void FrameCollector::recordWritten(Written&& written) {
  {
    std::lock_guard lock(mutex_);
    --queued_;
    if (written.error.empty()) {
      ++frames_;
      bytes_ += written.bytes;
      ++counters_.saved;
      counters_.last_saved = written.name;
    } else {
      ++counters_.refused;
    }
  }
  if (written.error.empty()) {
    spdlog::info("collect: saved {} into {}", written.name, options_.dir);
  } else if (on_error_) {
    on_error_("collect: " + written.name + " not saved: " + written.error);
  }
}

void FrameCollector::write(const Job& job) {
  const fs::path root(options_.dir);
  const std::string png = job.name + ".png";
  if (fs::exists(root / "rgb" / png)) throw Error((root / "rgb" / png).string() + " exists");
  const fs::path intrinsics_path = root / "intrinsics.yaml";
  const auto& k = job.frame.intrinsics;
  if (fs::exists(intrinsics_path)) {
    const CameraIntrinsics folder = readIntrinsics(intrinsics_path);
    if (!sameCamera(folder, k)) {
      throw Error(intrinsics_path.string() + ": the frame's camera (fx " + number(k.fx) +
                  ") is not the folder's (fx " + number(folder.fx) + "): one camera per folder");
    }
  } else {
    writeAtomically(intrinsics_path,
                    "# Pinhole intrinsics of the colour camera (pixels), depth registered\nfx: " +
                        number(k.fx) + "\nfy: " + number(k.fy) + "\ncx: " + number(k.cx) +
                        "\ncy: " + number(k.cy) + "\n");
  }
  // The images go in under .tmp/ and are renamed into place: a listing of rgb/
  // never shows half a PNG.
  const fs::path tmp_rgb = root / ".tmp" / ("rgb_" + png);
  const fs::path tmp_depth = root / ".tmp" / ("depth_" + png);
  try {
    writePngRgb(tmp_rgb.string(), Image<Rgb8>{job.frame.width, job.frame.height, job.frame.rgb});
    writePng16(tmp_depth.string(),
               Image<std::uint16_t>{job.frame.width, job.frame.height, job.frame.depth_mm});
    fs::rename(tmp_depth, root / "depth" / png);
    fs::rename(tmp_rgb, root / "rgb" / png);
    if (job.frame.extrinsics) {
      const CameraExtrinsics& e = *job.frame.extrinsics;
      appendRow(root / "extrinsics.csv", "name,height_m,pitch_rad,roll_rad",
                job.name + "," + number(e.height_m) + "," + number(e.pitch_rad) + "," +
                    number(e.roll_rad));
    }
    if (job.frame.gravity_up) {
      const auto& g = *job.frame.gravity_up;
      appendRow(root / "gravity.csv", "name,up_x,up_y,up_z",
                job.name + "," + number(g[0]) + "," + number(g[1]) + "," + number(g[2]));
    }
    appendRow(root / "frames.csv", kFramesHeader, job.name + "," + job.row);
  } catch (const std::exception& e) {
    std::error_code ec;
    for (const fs::path& p : {tmp_rgb, tmp_depth, root / "depth" / png, root / "rgb" / png}) {
      fs::remove(p, ec);
    }
    throw Error(std::string(e.what()));
  }
}

}  // namespace findmug::daemon
