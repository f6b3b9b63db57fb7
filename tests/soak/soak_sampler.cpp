// findmug-soak-sampler — samples a running findmugd during a soak (scripts/soak.sh).
//
//   findmug-soak-sampler --pid PID --url URL --duration 3600 --period 5
//       --csv soak.csv --svg soak.svg --summary soak.txt --warmup 60
//       [--max-rss-growth-mb 5] [--max-fd-growth 0] [--max-thread-growth 0] [--max-drops N]
//
// Every --period seconds it writes one CSV row: the daemon's RSS, open file
// descriptors and threads (from /proc/PID), and from its latest FINDMUG_STATUS
// the frame counters, rates, queue depths and the end-to-end latency
// percentiles. At the end (duration over, daemon gone, or SIGTERM/SIGINT) it
// draws the series as an SVG and judges the samples after --warmup: RSS growth
// (least-squares slope over the span, so that one allocation burst is not a
// trend), fd and thread ranges, and drops. Exits 0 when every given bound
// holds, 1 when one does not, 2 on usage errors or when no status ever arrived.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/subscriber.hpp"
#include "findmug/io/udpm.hpp"
#include "findmug_signals.hpp"

namespace {


struct Options {
  int pid = 0;
  std::string url;
  std::string channel = "FINDMUG_STATUS";
  double duration_s = 60, period_s = 5, warmup_s = 30;
  std::string csv, svg, summary;
  std::optional<double> max_rss_growth_mb;
  std::optional<long> max_fd_growth, max_thread_growth, max_drops;
};

struct Sample {
  double t_s = 0;
  long rss_kb = 0, fds = 0, threads = 0;
  long long received = 0, processed = 0, dropped = 0, rejected = 0, lost_in_transit = 0;
  double heap_mb = -1;  // daemon's heap in use (status), -1 unknown
  double input_fps = 0, output_fps = 0;
  long queue_total = 0, queue_max = 0;
  double lat_p50_ms = 0, lat_p95_ms = 0, lat_max_ms = 0;
  double load1 = 0;
};

[[noreturn]] void usage(const std::string& why) {
  std::cerr << "findmug-soak-sampler: " << why << "\n(see the top of tests/soak/soak_sampler.cpp)\n";
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) usage(flag + " needs a value");
    const std::string v = argv[++i];
    const auto number = [&flag, &v] {
      const auto x = findmug::parseNumber(v);
      if (!x) usage(flag + ": bad value '" + v + "'");
      return *x;
    };
    const auto integer = [&flag, &v] {
      const auto x = findmug::parseInteger(v);
      if (!x || *x < INT_MIN || *x > INT_MAX) usage(flag + ": bad value '" + v + "'");
      return static_cast<int>(*x);
    };
    if (flag == "--pid") o.pid = integer();
    else if (flag == "--url") o.url = v;
    else if (flag == "--channel") o.channel = v;
    else if (flag == "--duration") o.duration_s = number();
    else if (flag == "--period") o.period_s = number();
    else if (flag == "--warmup") o.warmup_s = number();
    else if (flag == "--csv") o.csv = v;
    else if (flag == "--svg") o.svg = v;
    else if (flag == "--summary") o.summary = v;
    else if (flag == "--max-rss-growth-mb") o.max_rss_growth_mb = number();
    else if (flag == "--max-fd-growth") o.max_fd_growth = integer();
    else if (flag == "--max-thread-growth") o.max_thread_growth = integer();
    else if (flag == "--max-drops") o.max_drops = integer();
    else usage("unknown flag " + flag);
  }
  if (o.pid <= 0 || o.csv.empty()) usage("--pid and --csv are required");
  if (!(o.period_s > 0) || !(o.duration_s > 0)) usage("--period and --duration must be > 0");
  return o;
}

// VmRSS and Threads from /proc/PID/status; false when the process is gone.
bool readProc(int pid, Sample& s) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  if (!in) return false;
  std::string key;
  while (in >> key) {
    if (key == "VmRSS:") in >> s.rss_kb;
    else if (key == "Threads:") in >> s.threads;
    in.ignore(1 << 20, '\n');
  }
  std::error_code ec;
  s.fds = 0;
  for (auto it = std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd", ec);
       !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
    ++s.fds;
  }
  std::ifstream("/proc/loadavg") >> s.load1;
  return s.rss_kb > 0;
}

void fillFromStatus(const findmug_lcm::status_t& st, Sample& s) {
  s.received = st.frames_received;
  s.processed = st.frames_processed;
  s.dropped = st.frames_dropped;
  s.rejected = st.frames_rejected;
  s.lost_in_transit = st.frames_lost_in_transit;
  s.heap_mb = st.heap_in_use_bytes >= 0 ? double(st.heap_in_use_bytes) / (1 << 20) : -1.0;
  s.input_fps = st.input_fps;
  s.output_fps = st.output_fps;
  for (int q = 0; q < st.num_queues; ++q) {
    s.queue_total += st.queue_depths[q];
    s.queue_max = std::max<long>(s.queue_max, st.queue_depths[q]);
  }
  int total = st.num_stages - 1;
  for (int k = 0; k < st.num_stages; ++k) {
    if (st.stage_names[k] == "total") total = k;
  }
  if (total >= 0) {
    s.lat_p50_ms = st.latency_p50_us[total] / 1000.0;
    s.lat_p95_ms = st.latency_p95_us[total] / 1000.0;
    s.lat_max_ms = st.latency_max_us[total] / 1000.0;
  }
}

// ---- SVG: one panel per quantity, time on x --------------------------------------

struct Series {
  std::string name, colour;
  std::vector<double> y;
};

void panel(std::ostream& out, double top, const std::string& title, const std::vector<double>& t,
           const std::vector<Series>& series) {
  const double left = 70, width = 820, height = 150;
  double lo = 1e300, hi = -1e300;
  for (const auto& s : series) {
    for (double v : s.y) lo = std::min(lo, v), hi = std::max(hi, v);
  }
  if (!(hi >= lo)) lo = 0, hi = 1;
  if (hi - lo < 1e-9) hi = lo + 1;
  const double t_end = t.empty() || t.back() <= 0 ? 1 : t.back();
  out << "<text x='" << left << "' y='" << top - 6 << "' font-size='13'>" << title << "</text>\n";
  out << "<rect x='" << left << "' y='" << top << "' width='" << width << "' height='" << height
      << "' fill='none' stroke='#888'/>\n";
  out << "<text x='" << left - 4 << "' y='" << top + 10 << "' font-size='10' text-anchor='end'>" << hi
      << "</text><text x='" << left - 4 << "' y='" << top + height
      << "' font-size='10' text-anchor='end'>" << lo << "</text>\n";
  double legend_x = left + 200;
  for (const auto& s : series) {
    out << "<polyline fill='none' stroke='" << s.colour << "' points='";
    for (std::size_t i = 0; i < s.y.size() && i < t.size(); ++i) {
      out << left + width * t[i] / t_end << "," << top + height - height * (s.y[i] - lo) / (hi - lo)
          << " ";
    }
    out << "'/>\n<text x='" << legend_x << "' y='" << top - 6 << "' font-size='11' fill='"
        << s.colour << "'>" << s.name << "</text>\n";
    legend_x += 110;
  }
}

void writeSvg(const std::string& path, const std::vector<Sample>& samples) {
  std::vector<double> t;
  auto col = [&samples](auto get) {
    std::vector<double> v;
    for (const auto& s : samples) v.push_back(get(s));
    return v;
  };
  t = col([](const Sample& s) { return s.t_s; });
  std::ofstream out(path);
  out << "<svg xmlns='http://www.w3.org/2000/svg' width='920' height='940' font-family='sans-serif'>\n"
      << "<rect width='100%' height='100%' fill='white'/>\n";
  panel(out, 30, "RSS (MB)", t, {{"rss", "#c00", col([](const Sample& s) { return s.rss_kb / 1024.0; })}});
  panel(out, 210, "open fds, threads", t,
        {{"fds", "#06c", col([](const Sample& s) { return double(s.fds); })},
         {"threads", "#090", col([](const Sample& s) { return double(s.threads); })}});
  panel(out, 390, "queue depth (sum, max)", t,
        {{"sum", "#06c", col([](const Sample& s) { return double(s.queue_total); })},
         {"max", "#c60", col([](const Sample& s) { return double(s.queue_max); })}});
  panel(out, 570, "latency total (ms)", t,
        {{"p50", "#090", col([](const Sample& s) { return s.lat_p50_ms; })},
         {"p95", "#c60", col([](const Sample& s) { return s.lat_p95_ms; })},
         {"max", "#c00", col([](const Sample& s) { return s.lat_max_ms; })}});
  panel(out, 750, "fps in/out, drops, load1", t,
        {{"in fps", "#06c", col([](const Sample& s) { return s.input_fps; })},
         {"out fps", "#090", col([](const Sample& s) { return s.output_fps; })},
         {"dropped", "#c00", col([](const Sample& s) { return double(s.dropped); })},
         {"load1", "#888", col([](const Sample& s) { return s.load1; })}});
  out << "<text x='70' y='925' font-size='11'>time (s), 0 .. " << (t.empty() ? 0 : t.back())
      << "</text>\n</svg>\n";
}

// Least-squares slope of y over t.
double slope(const std::vector<double>& t, const std::vector<double>& y) {
  const double n = static_cast<double>(t.size());
  if (n < 2) return 0;
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (std::size_t i = 0; i < t.size(); ++i) st += t[i], sy += y[i], stt += t[i] * t[i], sty += t[i] * y[i];
  const double d = n * stt - st * st;
  return d > 0 ? (n * sty - st * sy) / d : 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  const findmug::cli::StopSignals stop_signals;
  std::unique_ptr<findmug::io::Bus> bus;
  try {
    bus = findmug::io::openBus(o.url, "--url");
  } catch (const std::exception&) {
    usage("cannot open LCM at '" + o.url + "'");
  }
  // The latest status; this thread owns the bus (handle() below).
  findmug::io::Subscriber<findmug_lcm::status_t> listener(
      *bus, o.channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return findmug::io::decodeMessage<findmug_lcm::status_t>(d, n, c);
      },
      {}, [](const std::string& e) { std::cerr << "findmug-soak-sampler: " << e << "\n"; });

  std::ofstream csv(o.csv);
  csv << "t_s,rss_kb,fds,threads,received,processed,dropped,rejected,input_fps,output_fps,"
         "queue_depth_sum,queue_depth_max,latency_p50_ms,latency_p95_ms,latency_max_ms,load1,"
         "lost_in_transit,heap_in_use_mb\n";
  std::vector<Sample> samples;
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  bool alive = true;
  while (!stop_signals.requested()) {
    const auto now = std::chrono::steady_clock::now();
    const double t = std::chrono::duration<double>(now - start).count();
    if (now >= next) {
      Sample s;
      s.t_s = t;
      alive = readProc(o.pid, s);
      if (!alive) break;
      if (const auto latest = listener.latest()) fillFromStatus(*latest, s);
      samples.push_back(s);
      csv << s.t_s << "," << s.rss_kb << "," << s.fds << "," << s.threads << "," << s.received << ","
          << s.processed << "," << s.dropped << "," << s.rejected << "," << s.input_fps << ","
          << s.output_fps << "," << s.queue_total << "," << s.queue_max << "," << s.lat_p50_ms << ","
          << s.lat_p95_ms << "," << s.lat_max_ms << "," << s.load1 << "," << s.lost_in_transit
          << "," << s.heap_mb << std::endl;
      next += std::chrono::microseconds(static_cast<long long>(o.period_s * 1e6));
    }
    if (t >= o.duration_s) break;
    bus->handle(std::chrono::milliseconds(100));
  }
  if (!o.svg.empty()) writeSvg(o.svg, samples);

  // Judge the samples after warm-up.
  std::vector<double> t, rss, heap_t, heap;
  long fd_lo = 1L << 40, fd_hi = 0, th_lo = 1L << 40, th_hi = 0;
  double p95_max = 0;
  for (const auto& s : samples) {
    if (s.t_s < o.warmup_s) continue;
    t.push_back(s.t_s);
    rss.push_back(s.rss_kb / 1024.0);
    if (s.heap_mb >= 0) heap_t.push_back(s.t_s), heap.push_back(s.heap_mb);
    fd_lo = std::min(fd_lo, s.fds), fd_hi = std::max(fd_hi, s.fds);
    th_lo = std::min(th_lo, s.threads), th_hi = std::max(th_hi, s.threads);
    p95_max = std::max(p95_max, s.lat_p95_ms);
  }
  std::ostringstream report;
  bool ok = true;
  if (!listener.latest()) {
    std::cerr << "findmug-soak-sampler: no status message on " << o.channel << " in " << o.duration_s
              << " s\n";
    return 2;
  }
  const Sample& last = samples.back();
  const double span = t.size() >= 2 ? t.back() - t.front() : 0;
  const double growth_mb = slope(t, rss) * span;
  report << "samples " << samples.size() << " (" << t.size() << " after " << o.warmup_s
         << " s warm-up), span " << span << " s\n"
         << "rss after warm-up: first " << (rss.empty() ? 0 : rss.front()) << " MB, last "
         << (rss.empty() ? 0 : rss.back()) << " MB, trend " << growth_mb << " MB over the span\n"
         << "heap in use after warm-up (status): "
         << (heap.empty() ? std::string("unknown")
                          : "first " + std::to_string(heap.front()) + " MB, last " +
                                std::to_string(heap.back()) + " MB, max " +
                                std::to_string(*std::max_element(heap.begin(), heap.end())) +
                                " MB, trend " +
                                std::to_string(slope(heap_t, heap) * (heap_t.back() - heap_t.front())) +
                                " MB over the span")
         << "\n"
         << "fds " << fd_lo << ".." << fd_hi << ", threads " << th_lo << ".." << th_hi << "\n"
         << "frames received " << last.received << ", processed " << last.processed << ", dropped "
         << last.dropped << ", rejected " << last.rejected << ", lost in transit "
         << last.lost_in_transit << "\n"
         << "latency p95 (10 s windows) max " << p95_max << " ms; last p50 " << last.lat_p50_ms
         << " ms, p95 " << last.lat_p95_ms << " ms\n"
         << "daemon " << (alive ? "alive" : "GONE") << " at the end; status decode errors "
         << listener.rejected() << "\n";
  auto check = [&](bool good, const std::string& what) {
    if (!good) {
      ok = false;
      report << "FAIL: " << what << "\n";
    }
  };
  check(alive, "the daemon exited during the soak");
  check(listener.rejected() == 0, "undecodable status messages");
  if (o.max_rss_growth_mb) check(growth_mb <= *o.max_rss_growth_mb, "RSS trend above the bound");
  if (o.max_fd_growth) check(t.empty() || fd_hi - fd_lo <= *o.max_fd_growth, "fd count not flat");
  if (o.max_thread_growth) {
    check(t.empty() || th_hi - th_lo <= *o.max_thread_growth, "thread count not flat");
  }
  if (o.max_drops) check(last.dropped <= *o.max_drops, "more drops than allowed");
  std::cout << report.str();
  if (!o.summary.empty()) std::ofstream(o.summary) << report.str();
  return ok ? 0 : 1;
}
