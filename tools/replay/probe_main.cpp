// findmug-replay-probe — watches a running daemon over LCM during a replay and
// checks / measures what comes out (see replay_check.hpp for the verdicts).
//
//   findmug-replay-probe --url URL --log rec.lcm --name nyu-2x
//       --ready-file r --drained-file d --out-json nyu-2x.json --histogram-txt nyu-2x.txt
//
// It subscribes to FINDMUG_RGBD, FINDMUG_LABELS and FINDMUG_STATUS (with the
// channel suffix), and runs until SIGTERM/SIGINT; then it reads what is still
// queued (until the bus has been quiet for half a second), evaluates, writes
// its reports and exits 0 when every invariant holds, 1 otherwise (always 0
// with --report-only), 2 on usage or set-up errors.
//
// The replayed frames are either the FINDMUG_RGBD messages of a recorded log
// (--log: the ground truth of what was replayed), or, with --live, whatever
// appears on FINDMUG_RGBD; then --expect-file names a file in which the
// replayer writes how many frames it published, once it is done.
//
// Hand-shakes with the driver script (files, so that shell can wait on them):
//   --ready-file    created once a status message arrived: the daemon is up
//                   and (having opened its input first) subscribed;
//   --drained-file  created once the daemon's counters account for every
//                   replayed frame (published + dropped + rejected): the
//                   driver may stop the daemon without discarding anything.
//
//   findmug-replay-probe --inspect-log rec.lcm [--channel-suffix S]
// prints how many frames a log holds and at what rate, and exits.
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>  // lcm::LogFile for --inspect-log and --log
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/udpm.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug_cli.hpp"
#include "findmug_signals.hpp"
#include "replay_check.hpp"

namespace {

using findmug::Error;
using namespace findmug::replay;

// Set by main() to its StopSignals (made before anything starts a thread).
const findmug::cli::StopSignals* g_stop_signals = nullptr;
bool stopRequested() { return g_stop_signals != nullptr && g_stop_signals->requested(); }

struct Options {
  std::string url;
  std::string suffix;
  std::string name = "replay";
  std::string log;
  bool live = false;
  std::string expect_file;
  std::string ready_file;
  std::string drained_file;
  std::string out_json;
  std::string histogram_csv;
  std::string histogram_txt;
  double bin_ms = 100.0;
  int bins = 40;
  bool report_only = false;
  double timeout_s = 600.0;
  std::string inspect_log;
};

// The probe's flags; the --lcm-url/--url and --channel-suffix spellings come from the shared
// layer. Checks that need several flags at once are in checkOptions().
std::unique_ptr<CLI::App> makeProbeApp(Options& o) {
  auto app = findmug::cli::makeApp(
      "findmug-replay-probe",
      "Watches a running findmugd over LCM during a replay, checks what comes out and measures\n"
      "latency, fps and drops. Exit: 0 invariants held (or --report-only), 1 violated, 2 usage\n"
      "or set-up error. --inspect-log FILE prints how many frames a log holds and exits.");
  findmug::cli::addLcmUrlFlag(*app, o.url, "LCM URL to listen on");
  findmug::cli::addChannelSuffixFlag(*app, o.suffix);
  app->add_option("--name", o.name, "run name in reports");
  app->add_option("--log", o.log, "the replayed log: ground truth of the frames")
      ->type_name("FILE");
  app->add_flag("--live", o.live, "take the frames that appear on FINDMUG_RGBD instead of --log");
  app->add_option("--expect-file", o.expect_file,
                  "with --live: the replayer writes the number of frames it published here")
      ->type_name("F");
  app->add_option("--ready-file", o.ready_file, "created when the daemon's first status arrives")
      ->type_name("F");
  app->add_option("--drained-file", o.drained_file,
                  "created when the daemon has accounted for every replayed frame")
      ->type_name("F");
  app->add_option("--out-json", o.out_json, "figures and violations as JSON")->type_name("F");
  app->add_option("--histogram-csv", o.histogram_csv,
                  "latency histogram as CSV (from_ms,to_ms,count)")
      ->type_name("F");
  app->add_option("--histogram-txt", o.histogram_txt, "latency histogram as a text chart")
      ->type_name("F");
  app->add_option("--bin-ms", o.bin_ms, "histogram bin width")
      ->type_name("MS")
      ->check(findmug::cli::positive());
  app->add_option("--bins", o.bins, "number of histogram bins")->check(CLI::Range(2, 10000));
  app->add_flag("--report-only", o.report_only,
                "exit 0 even when invariants are violated (benchmarks)");
  app->add_option("--timeout", o.timeout_s, "stop by itself after S seconds")
      ->type_name("S")
      ->check(findmug::cli::positive());
  app->add_option("--inspect-log", o.inspect_log, "print the frame count and rate of a log, exit")
      ->type_name("FILE");
  return app;
}

void checkOptions(const Options& o) {
  if (!o.inspect_log.empty()) return;
  if (o.log.empty() == !o.live) throw Error("give exactly one of --log FILE and --live");
  if (!o.expect_file.empty() && !o.live) throw Error("--expect-file goes with --live");
}

FrameInfo frameInfo(const findmug_lcm::rgbd_frame_t& m) {
  return FrameInfo{m.seq, static_cast<std::uint64_t>(m.utime), m.width, m.height};
}

// The FINDMUG_RGBD frames of a log, in log order.
std::vector<FrameInfo> readLog(const std::string& path, const std::string& channel,
                               std::vector<std::int64_t>* event_times = nullptr) {
  if (!std::filesystem::is_regular_file(path)) throw Error(path + ": no such log file");
  lcm::LogFile log(path, "r");
  if (!log.good()) throw Error(path + ": cannot open as an LCM log");
  std::vector<FrameInfo> frames;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    if (event->channel != channel) continue;
    const auto msg = findmug::io::decodeMessage<findmug_lcm::rgbd_frame_t>(
        event->data, static_cast<std::size_t>(event->datalen),
        path + " event " + std::to_string(event->eventnum) + " on " + channel);
    frames.push_back(frameInfo(msg));
    if (event_times) event_times->push_back(event->timestamp);
  }
  return frames;
}

int inspectLog(const Options& o) {
  const std::string channel = findmug::io::channelName(findmug::io::kRgbdChannel, o.suffix);
  std::vector<std::int64_t> times;
  const auto frames = readLog(o.inspect_log, channel, &times);
  double rate = 0;
  if (times.size() >= 2 && times.back() > times.front()) {
    rate = static_cast<double>(times.size() - 1) /
           (static_cast<double>(times.back() - times.front()) / 1e6);
  }
  std::cout << "frames " << frames.size() << "\n"
            << "channel " << channel << "\n"
            << "rate_hz " << rate << "\n";
  if (!frames.empty()) {
    std::cout << "first_seq " << frames.front().seq << "\nlast_seq " << frames.back().seq << "\n"
              << "size " << frames.front().width << "x" << frames.front().height << "\n";
  }
  return 0;
}

void touch(const std::string& path) {
  if (path.empty()) return;
  std::ofstream f(path);
  if (!f) throw Error("cannot create " + path);
}

class Probe {
 public:
  Probe(const Options& o)
      : options_(o),
        rgbd_channel_(findmug::io::kRgbdChannel),
        labels_channel_(findmug::io::kLabelsChannel),
        status_channel_(findmug::io::kStatusChannel),
        bus_(findmug::io::openBus(o.url, "--url", o.suffix)) {  // the bus applies the suffix
    if (!o.log.empty()) {
      // A log file holds the names on the wire.
      const std::string logged = findmug::io::channelName(rgbd_channel_, o.suffix);
      for (const FrameInfo& f : readLog(o.log, logged)) check_.addReplayedFrame(f);
      if (check_.framesReplayed() == 0) throw Error(o.log + ": no frames on " + logged);
      expected_ = check_.framesReplayed();
    }
    // This thread owns the bus; the handlers run inside handle().
    auto handler = [this](void (Probe::*on)(const std::uint8_t*, std::size_t, const std::string&,
                                            std::int64_t)) {
      return [this, on](const std::string& ch, const std::uint8_t* d, std::size_t n,
                        std::int64_t recv_utime) { (this->*on)(d, n, ch, recv_utime); };
    };
    bus_->subscribeTimed(rgbd_channel_, handler(&Probe::onFrame));
    bus_->subscribeTimed(labels_channel_, handler(&Probe::onLabels));
    bus_->subscribeTimed(status_channel_, handler(&Probe::onStatus));
  }

  int run() {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(options_.timeout_s);
    bool timed_out = false;
    while (!stopRequested()) {
      // handle() returns every 100 ms at the latest: the loop condition sees a stop.
      const findmug::io::HandleResult rc = bus_->handle(std::chrono::milliseconds(100));
      if (rc == findmug::io::HandleResult::Failed || rc == findmug::io::HandleResult::EndOfLog) {
        throw Error("LCM receive failed");
      }
      if (std::chrono::steady_clock::now() > deadline) {
        timed_out = true;
        break;
      }
      pollExpectFile();
      if (!ready_ && check_.lastStatus()) {
        touch(options_.ready_file);
        ready_ = true;
      }
      if (!drained_ && expected_ && check_.drained(*expected_)) {
        touch(options_.drained_file);
        drained_ = true;
      }
    }
    // The daemon has exited (or we were told to stop): take what is queued.
    for (int quiet_ms = 0; quiet_ms < 500;) {
      const findmug::io::HandleResult rc = bus_->handle(std::chrono::milliseconds(100));
      if (rc == findmug::io::HandleResult::Failed || rc == findmug::io::HandleResult::EndOfLog) {
        break;
      }
      quiet_ms = rc == findmug::io::HandleResult::Timeout ? quiet_ms + 100 : 0;
    }
    pollExpectFile();
    if (timed_out) {
      check_.addViolation("timed out after " + std::to_string(options_.timeout_s) +
                          " s without being stopped");
    }
    if (options_.live && !expected_) {
      check_.addViolation("the replayer never reported how many frames it published (" +
                          options_.expect_file + "); using the frames seen on the bus");
    }
    const std::int64_t frames_in = expected_.value_or(check_.framesReplayed());
    const Report report = check_.evaluate(frames_in, CheckOptions{});
    writeReports(report);
    return report.ok() || options_.report_only ? 0 : 1;
  }

 private:
  void pollExpectFile() {
    if (options_.expect_file.empty() || expected_) return;
    std::ifstream f(options_.expect_file);
    long long n = -1;
    if (f >> n && n >= 0) expected_ = n;
  }

  void onFrame(const std::uint8_t* data, std::size_t size, const std::string& channel,
               std::int64_t recv_utime) {
    try {
      const auto msg = findmug::io::decodeMessage<findmug_lcm::rgbd_frame_t>(data, size, channel);
      check_.frameSeen(frameInfo(msg), recv_utime, options_.live);
    } catch (const Error& e) {
      check_.addViolation(std::string("undecodable frame on the bus: ") + e.what());
    }
  }

  void onLabels(const std::uint8_t* data, std::size_t size, const std::string& channel,
                std::int64_t recv_utime) {
    try {
      // Full decode: checks sizes, compression and every label id.
      const auto labels = findmug::io::decodeLabelImage(data, size, channel);
      const auto& ids = labels.image.labels;
      const bool all_void = std::all_of(ids.begin(), ids.end(),
                                        [](std::uint8_t id) { return id == findmug::kVoidLabel; });
      check_.labelReceived(LabelInfo{labels.seq, labels.utime, labels.image.width,
                                     labels.image.height, recv_utime, labels.latency_us, all_void});
    } catch (const Error& e) {
      check_.addViolation(std::string("label image does not decode: ") + e.what());
    }
  }

  void onStatus(const std::uint8_t* data, std::size_t size, const std::string& channel,
                std::int64_t) {
    try {
      const auto s = findmug::io::decodeMessage<findmug_lcm::status_t>(data, size, channel);
      StatusInfo info;
      info.utime = s.utime;
      info.frames_received = s.frames_received;
      info.frames_processed = s.frames_processed;
      info.frames_dropped = s.frames_dropped;
      info.frames_rejected = s.frames_rejected;
      info.source_state = s.source_state;
      info.semantic_map_frames = s.semantic_map_frames;
      info.semantic_map_skipped = s.semantic_map_skipped;
      info.semantic_map_voxels = s.semantic_map_voxels;
      info.object_frames = s.object_frames;
      info.object_frames_skipped = s.object_frames_skipped;
      info.object_candidates = s.object_candidates;
      info.objects_named = s.objects_named;
      info.mapped_objects = s.mapped_objects;
      info.object_map_publishes = s.object_map_publishes;
      for (int i = 0; i < s.num_stages; ++i) {
        info.stages.push_back({s.stage_names[i], s.latency_p50_us[i] / 1000.0,
                               s.latency_p95_us[i] / 1000.0, s.latency_max_us[i] / 1000.0});
      }
      check_.statusReceived(info);
    } catch (const Error& e) {
      check_.addViolation(std::string("status does not decode: ") + e.what());
    }
  }

  void writeReports(const Report& report) const {
    printReport(std::cout, options_.name, report);
    if (!options_.out_json.empty()) {
      std::ofstream f(options_.out_json);
      writeJson(f, options_.name, report);
    }
    if (!options_.histogram_csv.empty() || !options_.histogram_txt.empty()) {
      std::ofstream csv, txt;
      std::ostringstream discard;
      if (!options_.histogram_csv.empty()) csv.open(options_.histogram_csv);
      if (!options_.histogram_txt.empty()) txt.open(options_.histogram_txt);
      writeHistogram(options_.histogram_csv.empty() ? static_cast<std::ostream&>(discard) : csv,
                     options_.histogram_txt.empty() ? static_cast<std::ostream&>(discard) : txt,
                     options_.name, report, options_.bin_ms,
                     static_cast<std::size_t>(options_.bins));
    }
  }

  Options options_;
  std::string rgbd_channel_, labels_channel_, status_channel_;
  std::shared_ptr<findmug::io::Bus> bus_;  // owned by the thread that runs run()
  ReplayCheck check_;
  std::optional<std::int64_t> expected_;
  bool ready_ = false;
  bool drained_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  Options options;
  const auto app = makeProbeApp(options);
  if (auto code = findmug::cli::parse(*app, argc, argv)) return *code;
  try {
    checkOptions(options);
    if (!options.inspect_log.empty()) return inspectLog(options);
    const findmug::cli::StopSignals stop_signals;
    g_stop_signals = &stop_signals;
    Probe probe(options);
    return probe.run();
  } catch (const Error& e) {
    std::cerr << "findmug-replay-probe: " << e.what() << "\n";
    return 2;
  }
}
