// findmug-search-bench — object search in simulated multi-room apartments (issue 51):
// does a robot that looks on findmug's tables first find the mug sooner?
//
//   findmug-search-bench --apartments N --episodes-per-apartment K
//       --strategies findmug,places,coverage,random,oracle --perception oracle[,matcher]
//       [--models sim[,shipped]] [--drive-frames-hz 1] --jobs 2 --out DIR
//       [--config daemon/findmugd.yaml --model FILE --set KEY=VALUE ...]
//   findmug-search-bench ... --runs findmug/oracle/sim,coverage/oracle,findmug/matcher/sim ...
//
// A run is a strategy under one perception (and, where the daemon runs, one model): every
// strategy under every perception asked for; the findmug strategy once per model; the
// baselines under the matcher with the first model (their recogniser is the daemon's).
// --runs names the runs instead, by their labels STRATEGY/PERCEPTION[/MODEL]: the whole
// benchmark (five strategies and the perfect-table-map bound with the oracle recogniser,
// findmug with the matcher and each model) is one command and one pool of workers.
// With the matcher, "mug" is first taught (teach_mug.hpp) into a temporary objects_dir per
// model, from apartments whose seeds no episode uses.
//
// Writes DIR/episodes.csv (one row per run and episode), DIR/summary.md (the tables and
// paired ratios) and DIR/success_curve.svg. Runs of episodes run on --jobs workers; each is
// a pure function of its episode's seeds, so the output does not depend on --jobs.
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

#include <unistd.h>

#include "findmug/common/error.hpp"
#include "findmug_cli.hpp"
#include "report.hpp"
#include "strategies.hpp"
#include "teach_mug.hpp"

namespace {

using namespace findmug;
using namespace findmug::search;

std::string fixed2(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", v);
  return text;
}

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
  std::string models;  // "" = the one of --model
  std::string runs;    // "" = every strategy under every perception (--strategies, --perception)
  std::string out_dir;
  std::string config = "daemon/findmugd.yaml";
  std::string model = "models/findmug-apartments.fmf";
  std::vector<std::string> overrides = simDomainSettings();
  std::vector<std::string> extra_overrides;
  double budget_s = 600.0;
  double drive_frames_hz = 1.0;
  int teach_views = 3;
  std::uint64_t teach_seed = 7001;
  bool quiet = false;
  std::string trace_dir;  // "" = no traces
  double top_seen_share = 0.8;
  double room_seen_share = 0.8;
  bool no_replan = false;
  bool only_daemon_reachable = false;
  bool no_furniture_visits = false;
  bool full_look_arounds = false;
  bool keep_look_alikes = false;
  bool explore_to_room_centres = false;
  std::string only;  // "" = every episode
};

// A model the daemon runs with: its short name in the run labels, file and settings.
struct ModelChoice {
  std::string key, path;
  std::vector<std::string> overrides;
  std::unique_ptr<FindmugModel> loaded;
  std::string objects_dir;  // the taught mug (matcher)
  TaughtObject taught;
};

// One run: a strategy under one perception, with its model when the daemon runs.
struct RunSpec {
  std::string strategy, perception, model, label;
  Perception setup;
};

std::vector<std::string> splitWords(const std::string& text, const std::string& what) {
  std::vector<std::string> out;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');)
    if (!item.empty() && std::find(out.begin(), out.end(), item) == out.end())
      out.push_back(item);
  if (out.empty()) throw Error(what + ": nothing named");
  return out;
}

std::vector<ModelChoice> modelChoices(const Options& o) {
  std::vector<ModelChoice> out;
  if (o.models.empty()) {
    const std::string stem = std::filesystem::path(o.model).stem().string();
    const std::string key = stem == "findmug-apartments" && !o.overrides.empty() ? "sim"
                            : stem == "findmug" && o.overrides.empty()          ? "shipped"
                                                                                : stem;
    out.push_back({key, o.model, o.overrides, nullptr, "", {}});
    return out;
  }
  for (const std::string& key : splitWords(o.models, "--models")) {
    if (key == "sim")
      out.push_back({key, "models/findmug-apartments.fmf", simDomainSettings(), nullptr, "", {}});
    else if (key == "shipped")
      out.push_back({key, "models/findmug.fmf", {}, nullptr, "", {}});
    else
      throw Error("--models: unknown model '" + key +
                  "' (sim: models/findmug-apartments.fmf with its settings; shipped: "
                  "models/findmug.fmf, the NYU model, with the config's)");
  }
  return out;
}

// The row of one run on one episode. The world is built again for every run (a pure
// function of the episode's seeds, and cheap beside a run that feeds the daemon).
EpisodeRow runOnEpisode(const Episode& episode, const RunSpec& run, const SimParams& params) {
  const World world = makeWorld(episode, params);
  EpisodeRow row;
  row.episode = episode;
  row.run = run.label;
  row.perception = run.perception;
  row.model = run.model;
  row.rooms = static_cast<int>(world.apartment.rooms.size());
  row.mug_place = synth::mugPlaceName(world.mug.place);
  row.mug_room =
      world.mug.room >= 0 ? synth::roomKindName(world.apartment.rooms[world.mug.room].kind) : "-";
  row.shortest_path_m = world.shortest_path_m;
  row.look_alikes = world.mug.look_alikes_recoloured;
  row.result = runStrategy(run.strategy, world, params, run.setup);
  return row;
}

// Every run on every episode on `jobs` workers: the rows in the order of episodes, then runs.
std::vector<EpisodeRow> runAll(const std::vector<Episode>& episodes,
                               const std::vector<RunSpec>& runs, const SimParams& params,
                               int jobs, bool quiet) {
  // Work items of one run on one episode, not whole episodes: a run that feeds the daemon
  // takes seconds to minutes, an oracle-perception baseline milliseconds, so whole episodes
  // left one worker busy for minutes at the end. The longest runs go first for the same
  // reason: the matcher's (every frame through the daemon and a find request), then the
  // daemon's other runs, then the baselines. Rows keep the order of episodes, then runs,
  // whichever worker ran them.
  std::vector<std::size_t> run_order(runs.size());
  for (std::size_t r = 0; r < runs.size(); ++r) run_order[r] = r;
  const auto cost_rank = [&runs](std::size_t r) {
    return runs[r].setup.kind == Perception::Kind::Matcher ? 0
           : runs[r].setup.model != nullptr                ? 1
                                                           : 2;
  };
  std::stable_sort(run_order.begin(), run_order.end(),
                   [&](std::size_t a, std::size_t b) { return cost_rank(a) < cost_rank(b); });
  std::vector<std::pair<std::size_t, std::size_t>> items;  // (episode, run)
  for (const std::size_t r : run_order)
    for (std::size_t e = 0; e < episodes.size(); ++e) items.push_back({e, r});
  std::vector<std::vector<EpisodeRow>> results(episodes.size(),
                                               std::vector<EpisodeRow>(runs.size()));
  std::vector<std::size_t> runs_done(episodes.size(), 0);
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  std::string error;
  auto worker = [&] {
    for (std::size_t k; (k = next.fetch_add(1)) < items.size();) {
      const auto [i, r] = items[k];
      try {
        results[i][r] = runOnEpisode(episodes[i], runs[r], params);
      } catch (const std::exception& e) {
        std::lock_guard lock(mutex);
        if (error.empty()) {
          error = "episode " + std::to_string(episodes[i].apartment) + "." +
                  std::to_string(episodes[i].index) + ", run " + runs[r].label + ": " + e.what();
        }
        next = items.size();  // the other workers stop too
        return;
      }
      std::lock_guard lock(mutex);
      if (++runs_done[i] == runs.size() && !quiet)
        std::fprintf(stderr, "episode %zu/%zu (apartment %d, episode %d) done\n", i + 1,
                     episodes.size(), episodes[i].apartment, episodes[i].index);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::max(1, jobs); ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (!error.empty()) throw Error(error);

  std::vector<EpisodeRow> rows;
  for (const auto& r : results) rows.insert(rows.end(), r.begin(), r.end());
  return rows;
}

// The episodes named in --only ("A.E", apartment and episode index, comma-separated) among
// `all`: one episode of a large run again, with the same seeds. Throws findmug::Error
// naming an entry that is not "A.E" or not among them.
std::vector<Episode> onlyEpisodes(const std::vector<Episode>& all, const std::string& only) {
  std::vector<Episode> out;
  for (const std::string& item : splitWords(only, "--only")) {
    int a = -1, e = -1;
    char dot = 0, rest = 0;
    std::istringstream in(item);
    if (!(in >> a >> dot >> e) || dot != '.' || (in >> rest))
      throw Error("--only: '" + item + "' is not APARTMENT.EPISODE (e.g. 25.1)");
    const auto it = std::find_if(all.begin(), all.end(), [&](const Episode& x) {
      return x.apartment == a && x.index == e;
    });
    if (it == all.end())
      throw Error("--only: episode " + item + " is not in this run (--apartments, " +
                  "--episodes-per-apartment)");
    out.push_back(*it);
  }
  return out;
}

// One file per run and episode, named RUN_aA_eE.txt (slashes of the run label as '-').
void writeTraces(const std::string& dir, const std::vector<EpisodeRow>& rows) {
  std::filesystem::create_directories(dir);
  for (const EpisodeRow& row : rows) {
    std::string name = row.run;
    std::replace(name.begin(), name.end(), '/', '-');
    std::ofstream f(dir + "/" + name + "_a" + std::to_string(row.episode.apartment) + "_e" +
                    std::to_string(row.episode.index) + ".txt");
    f << row.run << ", apartment " << row.episode.apartment << " episode " << row.episode.index
      << ": mug on " << row.mug_place << " in the " << row.mug_room << "\n";
    for (const std::string& line : row.result.trace) f << line << "\n";
    if (!f) throw Error("--trace: cannot write into " + dir);
  }
}

// A run's perception and label; `model` is empty for a run without the daemon.
RunSpec runSpec(const std::string& strategy, const std::string& perception,
                const std::string& model) {
  RunSpec spec;
  spec.strategy = strategy;
  spec.perception = perception;
  spec.model = model;
  spec.setup.kind = perception == "matcher" ? Perception::Kind::Matcher : Perception::Kind::Oracle;
  spec.label = strategy + "/" + perception + (model.empty() ? "" : "/" + model);
  return spec;
}

void checkPerception(const std::string& p, const std::string& what) {
  if (p != "oracle" && p != "matcher")
    throw Error(what + ": unknown recogniser '" + p + "' (oracle, matcher)");
}

// Every strategy of --strategies under every perception of --perception; `models` gets
// those of --models (or --model).
std::vector<RunSpec> gridRuns(const Options& o, std::vector<ModelChoice>& models) {
  const std::vector<std::string> names = splitList(o.strategies);
  const std::vector<std::string> perceptions = splitWords(o.perception, "--perception");
  for (const std::string& p : perceptions) checkPerception(p, "--perception");
  models = modelChoices(o);
  std::vector<RunSpec> runs;
  for (const std::string& perception : perceptions)
    for (const std::string& name : names) {
      const bool daemon = name == "findmug" || perception == "matcher";
      if (!daemon) {
        runs.push_back(runSpec(name, perception, ""));
        continue;
      }
      // The findmug strategy once per model; a baseline with the first model's recogniser.
      const std::size_t n = name == "findmug" ? models.size() : 1;
      for (std::size_t m = 0; m < n; ++m) runs.push_back(runSpec(name, perception, models[m].key));
    }
  return runs;
}

// The runs --runs names by their labels, STRATEGY/PERCEPTION[/MODEL]; `models` gets the
// models they name (those of --models, or by default the ones named). Throws
// findmug::Error naming a label that is malformed, lacks the model a daemon run needs or
// names one a run without the daemon cannot use.
std::vector<RunSpec> namedRuns(const Options& o, std::vector<ModelChoice>& models) {
  if (o.strategies != Options{}.strategies || o.perception != Options{}.perception)
    throw Error("--runs names strategy and perception itself: leave out --strategies and "
                "--perception");
  std::vector<RunSpec> runs;
  std::vector<std::string> keys;
  for (const std::string& label : splitWords(o.runs, "--runs")) {
    std::vector<std::string> parts;
    std::stringstream s(label);
    for (std::string part; std::getline(s, part, '/');) parts.push_back(part);
    if (parts.size() < 2 || parts.size() > 3 ||
        std::any_of(parts.begin(), parts.end(), [](const std::string& x) { return x.empty(); }))
      throw Error("--runs: '" + label + "' is not STRATEGY/PERCEPTION[/MODEL] (e.g. "
                  "findmug/matcher/sim, coverage/oracle)");
    const std::string strategy = canonicalStrategy(parts[0]);
    checkPerception(parts[1], "--runs: '" + label + "'");
    const bool daemon = strategy == "findmug" || parts[1] == "matcher";
    if (daemon && parts.size() == 2)
      throw Error("--runs: '" + label + "' runs the daemon: name its model (" + label +
                  "/sim or " + label + "/shipped)");
    if (!daemon && parts.size() == 3)
      throw Error("--runs: '" + label + "' runs no daemon (the oracle recogniser, not the "
                  "findmug strategy): it takes no model");
    const std::string model = daemon ? parts[2] : "";
    if (daemon && std::find(keys.begin(), keys.end(), model) == keys.end()) keys.push_back(model);
    runs.push_back(runSpec(strategy, parts[1], model));
  }
  Options named = o;
  if (o.models.empty() && !keys.empty() && keys != std::vector<std::string>{modelChoices(o)[0].key}) {
    named.models.clear();
    for (const std::string& k : keys) named.models += (named.models.empty() ? "" : ",") + k;
  }
  models = keys.empty() ? std::vector<ModelChoice>{} : modelChoices(named);
  for (const std::string& k : keys)
    if (std::none_of(models.begin(), models.end(), [&k](const ModelChoice& m) { return m.key == k; }))
      throw Error("--runs: model '" + k + "' is not among --models");
  return runs;
}

int run(const Options& o) {
  SimParams params;
  params.time_budget_s = o.budget_s;
  params.drive_frames_hz = o.drive_frames_hz;
  params.trace = !o.trace_dir.empty();
  params.top_seen_share = o.top_seen_share;
  params.room_seen_share = o.room_seen_share;
  params.replan_on_new_tables = !o.no_replan;
  params.only_daemon_reachable = o.only_daemon_reachable;
  params.furniture_after_coverage = !o.no_furniture_visits;
  params.full_look_arounds = o.full_look_arounds;
  params.look_alikes = o.keep_look_alikes ? synth::LookAlikes::Keep : synth::LookAlikes::Recolour;
  params.explore_to_room_centres = o.explore_to_room_centres;
  std::vector<Episode> episodes;
  std::vector<std::uint64_t> apartment_seeds;
  for (int a = 0; a < o.apartments; ++a) {
    apartment_seeds.push_back(o.seed * 1000003ULL + a);
    for (int e = 0; e < o.episodes; ++e)
      episodes.push_back({a, e, o.seed * 1000003ULL + a, (o.seed * 1000003ULL + a) * 7919ULL + e});
  }
  if (!o.only.empty()) episodes = onlyEpisodes(episodes, o.only);

  std::vector<ModelChoice> models;
  std::vector<RunSpec> runs = o.runs.empty() ? gridRuns(o, models) : namedRuns(o, models);
  // Load the models the runs use; teach the mug with each one the matcher runs with.
  const std::filesystem::path scratch =
      std::filesystem::temp_directory_path() /
      ("findmug-search-bench-" + std::to_string(static_cast<long>(::getpid())));
  struct RemoveScratch {
    std::filesystem::path path;
    ~RemoveScratch() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  } remove_scratch{scratch};
  for (ModelChoice& m : models) {
    const bool used = std::any_of(runs.begin(), runs.end(),
                                  [&m](const RunSpec& r) { return r.model == m.key; });
    if (!used) continue;
    std::vector<std::string> overrides = m.overrides;
    overrides.insert(overrides.end(), o.extra_overrides.begin(), o.extra_overrides.end());
    m.loaded = std::make_unique<FindmugModel>(loadFindmugModel(o.config, m.path, overrides));
    const bool taught = std::any_of(runs.begin(), runs.end(), [&m](const RunSpec& r) {
      return r.model == m.key && r.perception == "matcher";
    });
    if (!taught) continue;
    m.objects_dir = (scratch / m.key).string();
    std::filesystem::create_directories(m.objects_dir);
    m.taught = teachTargetMug(*m.loaded, params, m.objects_dir, "mug", o.teach_views,
                              o.teach_seed, apartment_seeds);
  }
  for (RunSpec& r : runs) {
    for (const ModelChoice& m : models)
      if (m.key == r.model) r.setup.model = m.loaded.get(), r.setup.objects_dir = m.objects_dir;
  }
  std::vector<std::string> labels;
  for (const RunSpec& r : runs) labels.push_back(r.label);

  const std::vector<EpisodeRow> rows = runAll(episodes, runs, params, o.jobs, o.quiet);
  std::filesystem::create_directories(o.out_dir);
  if (!o.trace_dir.empty()) writeTraces(o.trace_dir, rows);
  std::ofstream csv(o.out_dir + "/episodes.csv");
  writeCsv(csv, rows);
  std::ofstream svg(o.out_dir + "/success_curve.svg");
  writeSuccessCurveSvg(svg, labels, rows, o.budget_s);
  std::ostringstream summary;
  summary << "Simulated object search: " << o.apartments << " apartments x " << o.episodes
          << " episodes, budget " << o.budget_s << " s; base " << params.speed_mps
          << " m/s, 45 deg/s; " << params.view_processing_s
          << " s per stop view; look-around " << params.look_around_views << " views"
          << (params.full_look_arounds
                  ? " (every heading)"
                  : " (findmug, places' fallback, random: only headings that show >= " +
                        fixed2(params.look_unseen_min_m2) + " m^2 of floor plan no frame showed "
                        "within " + fixed2(params.look_coverage_range_m) +
                        " m; coverage: every heading)")
          << "; ";
  if (params.drive_frames_hz > 0)
    summary << "frames while driving or turning every " << 1.0 / params.drive_frames_hz
            << " s of motion (processed in parallel to the motion: they cost no time; a find "
               "from one stops the robot there "
            << params.view_processing_s << " s later); ";
  else
    summary << "no frames while driving; ";
  summary << "runs are STRATEGY/PERCEPTION[/MODEL]. Oracle perception: >= "
          << params.recognise_min_pixels << " mug px within " << params.recognise_range_m
          << " m. The robot starts outside the mug's room; mug placements no pose can "
             "recognise (by the oracle) are drawn again. Mug prior: table "
          << params.prior.table << ", cabinet/shelf " << params.prior.cabinet << ", floor "
          << params.prior.floor << "; "
          << (params.look_alikes == synth::LookAlikes::Keep
                  ? "other mugs as red as the target kept (--keep-look-alikes)"
                  : "other mugs as red as the target recoloured (one mug looks like it)")
          << ".\n";
  for (const ModelChoice& m : models) {
    if (!m.loaded) continue;
    summary << "\nModel " << m.key << ": " << m.path << " (settings:";
    for (const std::string& s : m.overrides) summary << " " << s;
    for (const std::string& s : o.extra_overrides) summary << " " << s;
    summary << (m.overrides.empty() && o.extra_overrides.empty() ? " the config's)" : ")");
    if (!m.taught.views.empty()) {
      summary << "; matcher: \"mug\" taught from " << m.taught.views.size()
              << " views (apartment seed, camera to mug, candidate points):";
      for (const TaughtView& v : m.taught.views)
        summary << " " << v.apartment_seed << " " << fixed2(v.distance_m) << " m "
                << v.candidate_points << " pts;";
      summary << " \"seen\" counts as found within " << params.found_tolerance_m
              << " m of the mug (floor plane), else as a false \"found\" (a failure)";
    }
    summary << ".\n";
  }
  summary << "\n";
  writeSummary(summary, labels, rows, o.budget_s);
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
  app->add_option(
      "--strategies", o.strategies,
      "comma-separated: findmug|a, places|b, coverage|c, random|d, oracle|e, tables|f (a "
      "perfect table map: a bound, not in the default)");
  app->add_option("--perception", o.perception,
                  "mug recognition, comma-separated: oracle (rendered pixels), matcher "
                  "(findmugd's taught-object matcher and \"find mug\")");
  app->add_option("--runs", o.runs,
                  "the runs, comma-separated labels STRATEGY/PERCEPTION[/MODEL] (e.g. "
                  "findmug/oracle/sim,coverage/oracle,findmug/matcher/shipped), instead of every "
                  "strategy under every perception");
  app->add_option("--models", o.models,
                  "daemon models, comma-separated: sim (models/findmug-apartments.fmf, NYU and "
                  "rendered apartments, with its settings), shipped (models/findmug.fmf); "
                  "default: --model");
  app->add_option("--drive-frames-hz", o.drive_frames_hz,
                  "frames per second of motion while driving or turning (default 1; 0: views "
                  "at stops only)")
      ->check(CLI::Range(0.0, 30.0));
  app->add_option("--teach-views", o.teach_views, "views the mug is taught from (default 3)")
      ->check(CLI::Range(1, 10));
  app->add_option("--teach-seed", o.teach_seed,
                  "first apartment seed the mug is taught in (default 7001)");
  app->add_option("--jobs", o.jobs, "parallel episode workers (default 1)")->check(cli::positive());
  app->add_option("--seed", o.seed, "benchmark seed (default 1)");
  app->add_option("--budget", o.budget_s, "time budget per episode, simulated s (default 600)")
      ->check(cli::positive());
  app->add_option("--out", o.out_dir, "output folder")->required();
  app->add_option("--config", o.config, "findmugd config for the findmug strategy");
  app->add_option("--model", o.model,
                  "model for the findmug strategy (default models/findmug-apartments.fmf; "
                  "models/findmug.fmf for the cross-domain case, with --no-sim-settings)");
  app->add_flag_callback(
      "--no-sim-settings", [&o] { o.overrides.clear(); },
      "drop the sim-domain model's settings (learner.classes=labels, ...)");
  app->add_option("--set", o.extra_overrides, "KEY=VALUE daemon setting (repeatable)");
  app->add_flag("--quiet", o.quiet, "no progress lines");
  app->add_option("--top-seen-share", o.top_seen_share,
                  "findmug strategy: skip a table once this share of its top was in view within "
                  "the recogniser's reach (default 0.8; 0: visit every table)")
      ->check(CLI::Range(0.0, 1.0));
  app->add_option("--room-seen-share", o.room_seen_share,
                  "findmug and places strategies: a room counts as explored once the robot looked "
                  "around in it or its frames have shown this share of its floor plan (default "
                  "0.8; 1: only a look-around in it)")
      ->check(CLI::Range(0.0, 1.0));
  app->add_option("--only", o.only,
                  "run only these episodes of the run, APARTMENT.EPISODE comma-separated (e.g. "
                  "25.1,46.0), with the seeds they have in it");
  app->add_flag("--no-replan", o.no_replan,
                "findmug strategy: explore a room to its centre and look around even when the "
                "map shows a new table on the way");
  app->add_flag("--only-daemon-reachable", o.only_daemon_reachable,
                "findmug strategy: drive only to the search positions findmugd marks reachable, "
                "not, once every room is explored, to the others the robot's occupancy grid "
                "reaches");
  app->add_flag("--no-furniture-visits", o.no_furniture_visits,
                "findmug strategy: end when coverage has left nothing, instead of then looking at "
                "every footprint of the occupancy grid from beside it");
  app->add_flag("--full-look-arounds", o.full_look_arounds,
                "every look-around turns through all its headings, also those whose view would "
                "show nothing the robot's frames have not shown (the behaviour before look-arounds "
                "skipped them)");
  app->add_flag("--keep-look-alikes", o.keep_look_alikes,
                "keep the other mugs as red as the target (twins no recogniser can tell from it); "
                "by default they are recoloured");
  app->add_flag("--explore-to-room-centres", o.explore_to_room_centres,
                "findmug and places strategies: exploring a room drives to its centre before "
                "looking around, also when a spot on the way (its doorway) would show as much of "
                "it (the behaviour before exploring looked from the first such spot)");
  app->add_option("--trace", o.trace_dir,
                  "folder for one trace file per run and episode: every action with its time, "
                  "pose and reason");
  if (const auto code = cli::parse(*app, argc, argv)) return *code;
  spdlog::set_level(spdlog::level::warn);  // one pipeline per episode: its start/stop lines
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "findmug-search-bench: %s\n", e.what());
    return 2;
  }
}
