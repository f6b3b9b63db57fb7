// findmug-search-bench's CSV, summary, paired ratios and SVG curve (see report.hpp).
#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

namespace findmug::search {

namespace {

// Linear-interpolation quantile of a sorted sample (NaN when empty).
double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return std::nan("");
  const double pos = q * (sorted.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(pos));
  const std::size_t j = std::min(i + 1, sorted.size() - 1);
  return sorted[i] + (pos - i) * (sorted[j] - sorted[i]);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return quantile(v, 0.5);
}

std::string fixed(double v, int digits) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

std::vector<const EpisodeRow*> rowsOf(const std::string& strategy,
                                      const std::vector<EpisodeRow>& rows) {
  std::vector<const EpisodeRow*> out;
  for (const EpisodeRow& r : rows)
    if (r.label() == strategy) out.push_back(&r);
  return out;
}

const char* kColors[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#7f7f7f", "#ff7f0e"};

}  // namespace

double EpisodeRow::spl() const {
  if (!result.stats.found) return 0.0;
  return shortest_path_m / std::max(result.stats.path_m, shortest_path_m);
}

double EpisodeRow::censoredTime(double budget_s) const {
  return result.stats.found ? result.stats.found_time_s : budget_s;
}

void writeCsv(std::ostream& out, const std::vector<EpisodeRow>& rows) {
  out << "run,strategy,perception,model,apartment,episode,apartment_seed,episode_seed,rooms,"
         "mug_place,mug_room,shortest_m,found,false_found,time_s,path_m,views,drive_frames,"
         "recogniser_calls,drive_s,turn_s,process_s,spl,tables_mapped,positions_visited,"
         "frames_processed,look_closer,candidates,matches,refused_size,refused_colour,"
         "refused_shape,look_alikes\n";
  for (const EpisodeRow& r : rows) {
    const RunStats& s = r.result.stats;
    out << r.label() << ',' << r.result.strategy << ',' << r.perception << ',' << r.model << ','
        << r.episode.apartment << ',' << r.episode.index << ','
        << r.episode.apartment_seed << ',' << r.episode.episode_seed << ',' << r.rooms << ','
        << r.mug_place << ',' << r.mug_room << ',' << fixed(r.shortest_path_m, 3) << ','
        << (s.found ? 1 : 0) << ',' << (s.false_found ? 1 : 0) << ','
        << fixed(std::isfinite(s.found_time_s) ? s.found_time_s : s.time_s, 2) << ','
        << fixed(s.path_m, 3) << ',' << s.views << ',' << s.drive_frames << ','
        << s.recogniser_calls << ',' << fixed(s.drive_s, 2) << ',' << fixed(s.turn_s, 2) << ','
        << fixed(s.process_s, 2) << ',' << fixed(r.spl(), 4) << ',' << r.result.tables_mapped
        << ',' << r.result.positions_visited << ',' << r.result.frames_processed << ','
        << r.result.look_closer << ',' << r.result.candidates << ',' << r.result.matches << ','
        << r.result.refused_size << ',' << r.result.refused_colour << ','
        << r.result.refused_shape << ',' << r.look_alikes << '\n';
  }
}

StrategySummary summarise(const std::string& strategy, const std::vector<EpisodeRow>& rows) {
  StrategySummary s;
  s.strategy = strategy;
  std::vector<double> times, paths, views, drive_frames, calls;
  double spl = 0.0;
  for (const EpisodeRow* r : rowsOf(strategy, rows)) {
    ++s.episodes;
    spl += r->spl();
    views.push_back(r->result.stats.views);
    drive_frames.push_back(r->result.stats.drive_frames);
    calls.push_back(r->result.stats.recogniser_calls);
    s.false_found += r->result.stats.false_found;
    const bool on_table = r->mug_place == "table";
    s.table_episodes += on_table;
    s.table_found += on_table && r->result.stats.found;
    if (!r->result.stats.found) continue;
    ++s.found;
    times.push_back(r->result.stats.found_time_s);
    paths.push_back(r->result.stats.path_m);
  }
  if (s.episodes == 0) return s;
  s.success = static_cast<double>(s.found) / s.episodes;
  s.false_found_rate = static_cast<double>(s.false_found) / s.episodes;
  s.table_success =
      s.table_episodes ? static_cast<double>(s.table_found) / s.table_episodes : std::nan("");
  s.spl = spl / s.episodes;
  std::sort(times.begin(), times.end());
  std::sort(paths.begin(), paths.end());
  s.time_median = quantile(times, 0.5), s.time_q1 = quantile(times, 0.25);
  s.time_q3 = quantile(times, 0.75);
  s.path_median = quantile(paths, 0.5), s.path_q1 = quantile(paths, 0.25);
  s.path_q3 = quantile(paths, 0.75);
  s.views_median = median(views);
  s.drive_frames_median = median(drive_frames);
  s.recogniser_calls_median = median(calls);
  return s;
}

PairedRatio pairedTimeRatio(const std::string& reference, const std::string& other,
                            const std::vector<EpisodeRow>& rows, double budget_s, int resamples) {
  PairedRatio p{reference, other};
  std::vector<double> ratios;
  for (const EpisodeRow* a : rowsOf(reference, rows))
    for (const EpisodeRow* b : rowsOf(other, rows))
      if (a->episode.apartment == b->episode.apartment && a->episode.index == b->episode.index)
        ratios.push_back(b->censoredTime(budget_s) / std::max(1e-3, a->censoredTime(budget_s)));
  p.pairs = static_cast<int>(ratios.size());
  if (ratios.empty()) return p;
  p.median = median(ratios);
  std::vector<double> medians;
  std::uint64_t state = 0x243f6a8885a308d3ULL;  // fixed: the same interval every run
  std::vector<double> sample(ratios.size());
  for (int k = 0; k < resamples; ++k) {
    for (double& v : sample) {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      v = ratios[(state >> 33) % ratios.size()];
    }
    medians.push_back(median(sample));
  }
  std::sort(medians.begin(), medians.end());
  p.lo = quantile(medians, 0.025);
  p.hi = quantile(medians, 0.975);
  return p;
}

void writeSuccessCurveSvg(std::ostream& out, const std::vector<std::string>& strategies,
                          const std::vector<EpisodeRow>& rows, double budget_s) {
  const double W = 640, H = 400, L = 60, R = 150, T = 20, B = 50;
  auto x = [&](double t) { return L + (W - L - R) * t / budget_s; };
  auto y = [&](double f) { return H - B - (H - T - B) * f; };
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (int k = 0; k <= 4; ++k) {  // axes and grid
    const double f = k / 4.0, t = budget_s * k / 4.0;
    out << "<line x1=\"" << L << "\" x2=\"" << W - R << "\" y1=\"" << y(f) << "\" y2=\"" << y(f)
        << "\" stroke=\"#ddd\"/><text x=\"" << L - 8 << "\" y=\"" << y(f) + 4
        << "\" text-anchor=\"end\">" << fixed(f, 2) << "</text>\n"
        << "<text x=\"" << x(t) << "\" y=\"" << H - B + 16 << "\" text-anchor=\"middle\">"
        << fixed(t, 0) << "</text>\n";
  }
  out << "<text x=\"" << (L + W - R) / 2 << "\" y=\"" << H - 10
      << "\" text-anchor=\"middle\">time budget (s, simulated)</text>\n"
      << "<text x=\"14\" y=\"" << (T + H - B) / 2 << "\" transform=\"rotate(-90 14 "
      << (T + H - B) / 2 << ")\" text-anchor=\"middle\">success rate</text>\n";
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    std::vector<double> times;
    const auto mine = rowsOf(strategies[k], rows);
    for (const EpisodeRow* r : mine)
      if (r->result.stats.found) times.push_back(r->result.stats.found_time_s);
    std::sort(times.begin(), times.end());
    const double n = std::max<std::size_t>(1, mine.size());
    const char* color = kColors[k % 6];
    out << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"2\" points=\"" << x(0)
        << ',' << y(0);
    for (std::size_t i = 0; i < times.size(); ++i)  // a step up at each find
      out << ' ' << x(times[i]) << ',' << y(i / n) << ' ' << x(times[i]) << ',' << y((i + 1) / n);
    out << ' ' << x(budget_s) << ',' << y(times.size() / n) << "\"/>\n"
        << "<text x=\"" << W - R + 8 << "\" y=\"" << T + 16 * (k + 1) << "\" fill=\"" << color
        << "\">" << strategies[k] << "</text>\n";
  }
  out << "</svg>\n";
}

void writeSummary(std::ostream& out, const std::vector<std::string>& strategies,
                  const std::vector<EpisodeRow>& rows, double budget_s) {
  out << "| run | episodes | success | success, mug on a table | false \"found\" | SPL | "
         "time to find, median [IQR] s | path, median [IQR] m | views (median) | "
         "driving frames (median) | recogniser calls (median) |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& name : strategies) {
    const StrategySummary s = summarise(name, rows);
    out << "| " << name << " | " << s.episodes << " | " << fixed(s.success, 3) << " | "
        << fixed(s.table_success, 3) << " (" << s.table_found << "/" << s.table_episodes
        << ") | " << fixed(s.false_found_rate, 3) << " (" << s.false_found << ") | "
        << fixed(s.spl, 3) << " | " << fixed(s.time_median, 1) << " [" << fixed(s.time_q1, 1)
        << ", " << fixed(s.time_q3, 1) << "] | " << fixed(s.path_median, 1) << " ["
        << fixed(s.path_q1, 1) << ", " << fixed(s.path_q3, 1) << "] | " << fixed(s.views_median, 0)
        << " | " << fixed(s.drive_frames_median, 0) << " | "
        << fixed(s.recogniser_calls_median, 0) << " |\n";
  }
  // Success and median time (failures at the budget) by where the mug stood.
  std::vector<std::string> places;
  for (const EpisodeRow& r : rows)
    if (std::find(places.begin(), places.end(), r.mug_place) == places.end())
      places.push_back(r.mug_place);
  std::sort(places.begin(), places.end(), [](const std::string& a, const std::string& b) {
    auto rank = [](const std::string& p) { return p == "table" ? 0 : p == "cabinet" ? 1 : 2; };
    return rank(a) < rank(b);
  });
  out << "\nSuccess (median time to find, failures at " << fixed(budget_s, 0)
      << " s) by where the mug stood:\n\n| run |";
  for (const std::string& p : places) out << " mug on " << p << " |";
  out << "\n|---|";
  for (std::size_t k = 0; k < places.size(); ++k) out << "---|";
  out << "\n";
  for (const std::string& name : strategies) {
    out << "| " << name << " |";
    for (const std::string& p : places) {
      int n = 0, found = 0;
      std::vector<double> times;
      for (const EpisodeRow* r : rowsOf(name, rows)) {
        if (r->mug_place != p) continue;
        ++n;
        found += r->result.stats.found;
        times.push_back(r->censoredTime(budget_s));
      }
      out << " " << found << "/" << n << " (" << fixed(median(times), 1) << " s) |";
    }
    out << "\n";
  }
  if (strategies.size() < 2) return;
  out << "\nPaired time ratio other/" << strategies.front()
      << " per episode (failures at the budget " << fixed(budget_s, 0)
      << " s), median with bootstrap 95 % CI:\n\n| other | pairs | median ratio | 95 % CI |\n"
         "|---|---|---|---|\n";
  for (std::size_t k = 1; k < strategies.size(); ++k) {
    const PairedRatio p = pairedTimeRatio(strategies.front(), strategies[k], rows, budget_s);
    out << "| " << p.other << " | " << p.pairs << " | " << fixed(p.median, 2) << " | ["
        << fixed(p.lo, 2) << ", " << fixed(p.hi, 2) << "] |\n";
  }
}

}  // namespace findmug::search
