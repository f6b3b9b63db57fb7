// findmug-search-bench — object search in simulated multi-room apartments (issue 51):
// does a robot that looks on findmug's tables first find the mug sooner?
//
//   findmug-search-bench --apartments N --episodes-per-apartment K
//       --strategies findmug,places,coverage,random,oracle --perception oracle
//       --jobs 2 --out DIR [--config daemon/findmugd.yaml --model models/findmug-nyu-synth.fmf
//       --set KEY=VALUE ...]
//
// Writes DIR/episodes.csv (one row per strategy and episode), DIR/summary.md (the table
// and paired ratios) and DIR/success_curve.svg. Episodes run on --jobs workers; each is a
// pure function of its seeds, so the output does not depend on --jobs.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug_cli.hpp"
#include "report.hpp"
#include "strategies.hpp"

namespace {

using namespace findmug;
using namespace findmug::search;

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');)
    if (!item.empty()) out.push_back(canonicalStrategy(item));
  if (out.empty()) throw Error("--strategies: no strategy named");
  return out;
}

struct Options {
  int apartments = 2, episodes = 2, jobs = 1;
  std::uint64_t seed = 1;
  std::string strategies = "findmug,places,coverage,random,oracle";
  std::string perception = "oracle";
  std::string out_dir;
  std::string config = "daemon/findmugd.yaml";
  std::string model = "models/findmug-nyu-synth.fmf";
  // demo.sh's settings for the sim-domain model.
  std::vector<std::string> overrides{"learner.classes=labels", "features.objects=false",
                                     "mrf.pairwise=potts"};
  std::vector<std::string> extra_overrides;
  double budget_s = 600.0;
  bool quiet = false;
};

// All rows of one episode, every strategy in the order asked for.
std::vector<EpisodeRow> runEpisode(const Episode& episode, const std::vector<std::string>& names,
                                   const SimParams& params, const FindmugModel* model) {
  const World world = makeWorld(episode, params);
  std::vector<EpisodeRow> rows;
  for (const std::string& name : names) {
    EpisodeRow row;
    row.episode = episode;
    row.rooms = static_cast<int>(world.apartment.rooms.size());
    row.mug_place = synth::mugPlaceName(world.mug.place);
    row.mug_room =
        world.mug.room >= 0 ? synth::roomKindName(world.apartment.rooms[world.mug.room].kind) : "-";
    row.shortest_path_m = world.shortest_path_m;
    row.result = runStrategy(name, world, params, model);
    rows.push_back(row);
  }
  return rows;
}

int run(const Options& o) {
  const std::vector<std::string> names = splitList(o.strategies);
  if (o.perception != "oracle")
    throw Error("--perception: only 'oracle' recognition of the mug is implemented");
  SimParams params;
  params.time_budget_s = o.budget_s;
  std::unique_ptr<FindmugModel> model;
  if (std::find(names.begin(), names.end(), "findmug") != names.end()) {
    std::vector<std::string> overrides = o.overrides;
    overrides.insert(overrides.end(), o.extra_overrides.begin(), o.extra_overrides.end());
    model = std::make_unique<FindmugModel>(loadFindmugModel(o.config, o.model, overrides));
  }
  std::vector<Episode> episodes;
  for (int a = 0; a < o.apartments; ++a)
    for (int e = 0; e < o.episodes; ++e)
      episodes.push_back({a, e, o.seed * 1000003ULL + a, (o.seed * 1000003ULL + a) * 7919ULL + e});
  std::vector<std::vector<EpisodeRow>> results(episodes.size());
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  std::string error;
  auto worker = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < episodes.size();) {
      try {
        results[i] = runEpisode(episodes[i], names, params, model.get());
      } catch (const std::exception& e) {
        std::lock_guard lock(mutex);
        if (error.empty()) error = e.what();
        return;
      }
      if (!o.quiet) {
        std::lock_guard lock(mutex);
        std::fprintf(stderr, "episode %zu/%zu (apartment %d, episode %d) done\n", i + 1,
                     episodes.size(), episodes[i].apartment, episodes[i].index);
      }
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::max(1, o.jobs); ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (!error.empty()) throw Error(error);

  std::vector<EpisodeRow> rows;
  for (const auto& r : results) rows.insert(rows.end(), r.begin(), r.end());
  std::filesystem::create_directories(o.out_dir);
  std::ofstream csv(o.out_dir + "/episodes.csv");
  writeCsv(csv, rows);
  std::ofstream svg(o.out_dir + "/success_curve.svg");
  writeSuccessCurveSvg(svg, names, rows, o.budget_s);
  std::ostringstream summary;
  summary << "Simulated object search: " << o.apartments << " apartments x " << o.episodes
          << " episodes, budget " << o.budget_s << " s; base " << params.speed_mps
          << " m/s, 45 deg/s; " << params.view_processing_s << " s per view; look-around "
          << params.look_around_views
          << " views; oracle mug recognition (>= " << params.recognise_min_pixels << " px within "
          << params.recognise_range_m
          << " m). The robot starts outside the mug's room; mug placements no pose can "
             "recognise are drawn again. Mug prior: table "
          << params.prior.table << ", cabinet/shelf " << params.prior.cabinet << ", floor "
          << params.prior.floor << ".\n\n";
  writeSummary(summary, names, rows, o.budget_s);
  std::ofstream(o.out_dir + "/summary.md") << summary.str();
  if (!csv || !svg) throw Error("cannot write the results into " + o.out_dir);
  std::cout << summary.str();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  auto app = cli::makeApp("findmug-search-bench",
                          "Object search in simulated multi-room apartments: findmug's tables "
                          "against baselines, on the same seeded episodes");
  app->add_option("--apartments", o.apartments, "apartments (default 2)")->check(cli::positive());
  app->add_option("--episodes-per-apartment", o.episodes, "episodes per apartment (default 2)")
      ->check(cli::positive());
  app->add_option("--strategies", o.strategies,
                  "comma-separated: findmug|a, places|b, coverage|c, random|d, oracle|e");
  app->add_option("--perception", o.perception, "mug recognition: oracle (the only one)");
  app->add_option("--jobs", o.jobs, "parallel episode workers (default 1)")->check(cli::positive());
  app->add_option("--seed", o.seed, "benchmark seed (default 1)");
  app->add_option("--budget", o.budget_s, "time budget per episode, simulated s (default 600)")
      ->check(cli::positive());
  app->add_option("--out", o.out_dir, "output folder")->required();
  app->add_option("--config", o.config, "findmugd config for the findmug strategy");
  app->add_option("--model", o.model,
                  "model for the findmug strategy (default models/findmug-nyu-synth.fmf; "
                  "models/findmug.fmf for the cross-domain case, with --no-sim-settings)");
  app->add_flag_callback(
      "--no-sim-settings", [&o] { o.overrides.clear(); },
      "drop demo.sh's settings for the sim-domain model");
  app->add_option("--set", o.extra_overrides, "KEY=VALUE daemon setting (repeatable)");
  app->add_flag("--quiet", o.quiet, "no progress lines");
  if (const auto code = cli::parse(*app, argc, argv)) return *code;
  spdlog::set_level(spdlog::level::warn);  // one pipeline per episode: its start/stop lines
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "findmug-search-bench: %s\n", e.what());
    return 2;
  }
}
