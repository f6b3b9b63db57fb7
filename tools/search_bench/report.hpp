// report.hpp — findmug-search-bench's results: the per-episode CSV, the summary per run
// (a strategy under one perception, and for the daemon's runs one model: success overall and
// on table episodes, false "found" rate, SPL, median and IQR of time and path to find, views,
// driving frames and recogniser calls), success by where the mug stood, paired
// differences against a reference strategy with a bootstrap 95 % interval, and the
// success-against-time curve as SVG.
//
// Why paired: every strategy runs on the same episodes, so per-episode ratios remove the
// apartment-to-apartment spread that dominates unpaired medians.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "strategies.hpp"

namespace findmug::search {

// One row of the CSV: a strategy's run of one episode and the episode's facts.
struct EpisodeRow {
  Episode episode;
  // What the summary groups by: "strategy/perception[/model]" ("" = result.strategy).
  std::string run, perception, model;
  int rooms = 0;
  std::string mug_place, mug_room;
  int look_alikes = 0;  // other red mugs recoloured (synth::LookAlikes)
  double shortest_path_m = 0.0;
  EpisodeResult result;
  double spl() const;
  // Time to find, the budget when not found (the censored value the paired ratios use).
  double censoredTime(double budget_s) const;
  const std::string& label() const { return run.empty() ? result.strategy : run; }
};

void writeCsv(std::ostream& out, const std::vector<EpisodeRow>& rows);

struct StrategySummary {
  std::string strategy;
  int episodes = 0, found = 0, false_found = 0;
  int table_episodes = 0, table_found = 0;  // the mug on a table
  double success = 0.0, spl = 0.0, false_found_rate = 0.0, table_success = 0.0;
  double time_median = 0.0, time_q1 = 0.0, time_q3 = 0.0;  // over successes
  double path_median = 0.0, path_q1 = 0.0, path_q3 = 0.0;  // over successes
  double views_median = 0.0;                               // over all episodes
  double drive_frames_median = 0.0, recogniser_calls_median = 0.0;  // over all episodes
};

StrategySummary summarise(const std::string& strategy, const std::vector<EpisodeRow>& rows);

// Median over episodes of time(other) / time(reference), failures at the budget, with a
// percentile bootstrap 95 % interval (deterministic resampling).
struct PairedRatio {
  std::string reference, other;
  int pairs = 0;
  double median = 0.0, lo = 0.0, hi = 0.0;
};

PairedRatio pairedTimeRatio(const std::string& reference, const std::string& other,
                            const std::vector<EpisodeRow>& rows, double budget_s,
                            int resamples = 2000);

// Fraction of episodes found by time t, t from 0 to the budget, one line per strategy.
void writeSuccessCurveSvg(std::ostream& out, const std::vector<std::string>& strategies,
                          const std::vector<EpisodeRow>& rows, double budget_s);

// The summary as Markdown tables: per run, success by the mug's place, the paired ratios.
void writeSummary(std::ostream& out, const std::vector<std::string>& strategies,
                  const std::vector<EpisodeRow>& rows, double budget_s);

}  // namespace findmug::search
