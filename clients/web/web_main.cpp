// findmug-web — watch findmugd live in a browser (and, through the same server, its data
// folders).
//
// Subscribes to FINDMUG_LABELS, FINDMUG_TABLES, FINDMUG_TABLE_MAP, FINDMUG_SEMANTIC_MAP
// and FINDMUG_STATUS (with --channel-suffix) through findmug's own bus and hardened
// decoders, keeps the latest of each (live_state.hpp) and serves a page that draws them
// several times a second (static/: HTML, JS and CSS, no network needed); publishes the
// page's requests to the daemon (Save this frame, reload a model) on FINDMUG_COMMAND.
// Listens on 127.0.0.1 unless the config (web.bind) or --bind names another address; then
// the token of --token-file is required on every request (web_server.hpp has the access
// rules).
#include <cstdio>
#include <iostream>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "client_common.hpp"
#include "findmug/common/error.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/io/subscriber.hpp"
#include "findmug_cli.hpp"
#include "live_state.hpp"
#include "web_config.hpp"
#include "web_server.hpp"

#ifndef FINDMUG_WEB_STATIC_DIR
#define FINDMUG_WEB_STATIC_DIR "/usr/share/findmug/web"
#endif

namespace {

using namespace findmug;
constexpr const char* kProgram = "findmug-web";

// The command line; empty / 0 means "as the config says".
struct WebFlags {
  std::string url, suffix, bind, token_file, static_dir, model_path, nyu_rotations;
  std::vector<std::string> data_dirs;
  int port = 0;
  cli::ConfigFlags config;
};

void addFlags(CLI::App& app, WebFlags& f) {
  cli::addConfigFlags(app, f.config, "YAML config (its web: section)");
  cli::addLcmUrlFlag(app, f.url, "LCM provider (default: LCM_DEFAULT_URL or udpm default)");
  cli::addChannelSuffixFlag(app, f.suffix);
  app.add_option("--port", f.port, "TCP port (default web.port, 8088)")
      ->check(CLI::Range(1, 65535));
  app.add_option("--bind", f.bind,
                 "address to listen on (default web.bind, 127.0.0.1); any other than "
                 "127.0.0.1/::1/localhost needs --token-file")
      ->type_name("ADDR");
  app.add_option("--token-file", f.token_file,
                 "file with the access token (owner-only permissions); required on every "
                 "request when given")
      ->type_name("FILE");
  app.add_option("--data", f.data_dirs, "data folders the page may read and label (repeatable)")
      ->type_name("DIR");
  app.add_option("--static-dir", f.static_dir,
                 "the page's files (default web.static_dir, or " FINDMUG_WEB_STATIC_DIR ")")
      ->type_name("DIR");
  app.add_option("--model", f.model_path,
                 "model the Label page's prediction comes from (default web.model_path)")
      ->type_name("FILE");
  app.add_option("--nyu-rotations", f.nyu_rotations,
                 "NYU's camera_rotations_NYU.txt (default web.nyu_rotations)")
      ->type_name("FILE");
}

// Reads the config (its segmenter sections for the Label page's prediction, and web:),
// lets the flags override it and checks the result. Throws findmug::Error naming the
// setting or file at fault.
web::ServerOptions serverOptions(const WebFlags& f, web::WebConfig& config) {
  Config loaded;
  SettingsSchema schema;
  bindCoreSettings(schema, loaded);
  schema.bind(web::webSettings(), config);
  cli::readSettings(f.config, schema);
  if (!f.bind.empty()) config.bind = f.bind;
  if (f.port != 0) config.port = f.port;
  if (!f.token_file.empty()) config.token_file = f.token_file;
  if (!f.static_dir.empty()) config.static_dir = f.static_dir;
  if (!f.model_path.empty()) config.model_path = f.model_path;
  if (!f.nyu_rotations.empty()) config.nyu_rotations = f.nyu_rotations;
  io::checkChannelSuffix(f.suffix);
  web::ServerOptions options;
  options.bind = config.bind;
  options.port = config.port;
  options.max_body_bytes = static_cast<std::size_t>(config.max_body_bytes);
  options.static_dir = config.static_dir.empty() ? FINDMUG_WEB_STATIC_DIR : config.static_dir;
  for (const auto& d : f.data_dirs) options.data_dirs.emplace_back(d);
  options.segmenter = loaded.segmenter;
  if (!config.model_path.empty()) {
    options.model = std::make_shared<const RandomForest>(RandomForest::load(config.model_path));
    options.model_name =
        std::filesystem::path(config.model_path).filename().string() + ":" + options.model->id();
    // The settings the model records are the defaults of the keys it records (refused here,
    // at start, when the config gives one another value).
    options.segmenter = configForModel(loaded.segmenter, *options.model);
  }
  if (!config.nyu_rotations.empty()) options.nyu_rotations = config.nyu_rotations;
  if (!config.token_file.empty()) {
    options.token = web::readTokenFile(config.token_file);
  } else if (!web::isDefaultLoopback(config.bind)) {
    throw Error("listening on " + config.bind +
                " needs an access token: give --token-file (or web.token_file)");
  }
  return options;
}

// The Retrain page's jobs (none without web.jobs_dir). The tools read the same config
// findmug-web was given (the daemon's settings).
std::unique_ptr<web::RetrainJobs> retrainJobs(const web::WebConfig& config,
                                              const cli::ConfigFlags& config_flags,
                                              const web::ServerOptions& options) {
  if (config.jobs_dir.empty()) return nullptr;
  web::RetrainOptions r;
  r.train_program = config.train_program;
  r.eval_program = config.eval_program;
  r.jobs_dir = config.jobs_dir;
  r.install_path = config.install_path;
  r.folds = config.retrain_folds;
  if (config_flags.config_path) r.config_args = {"--config", *config_flags.config_path};
  for (const auto& o : config_flags.overrides) {
    r.config_args.push_back("--set");
    r.config_args.push_back(o);
  }
  // A retrained model computes the features the running one does: the settings the model
  // records, which the config may not give (configForModel).
  if (options.model) {
    RandomForest::Settings recorded = extractionSettings(options.segmenter);
    recorded.emplace_back("learner.kind", learnerKindName(options.segmenter.learner.kind));
    recorded.emplace_back("learner.classes", classSchemeName(options.segmenter.learner.classes));
    for (const auto& [key, value] : recorded) {
      r.config_args.push_back("--set");
      r.config_args.push_back(key + "=" + value);
    }
  }
  // NYU frames get their gravity from NYU's rotations in training as on the Label page.
  if (!config.nyu_rotations.empty()) {
    r.config_args.insert(r.config_args.end(), {"--nyu-rotations", config.nyu_rotations});
  }
  return std::make_unique<web::RetrainJobs>(std::move(r));
}

// Base names: the bus applies --channel-suffix (io::SuffixedBus).
const std::string kLabels(io::kLabelsChannel), kTables(io::kTablesChannel),
    kTableMap(io::kTableMapChannel), kSemanticMap(io::kSemanticMapChannel),
    kStatus(io::kStatusChannel), kCommand(io::kCommandChannel), kObjects(io::kObjectsChannel),
    kFindResult(io::kFindResultChannel);

template <class Message, class Decode, class Keep>
std::unique_ptr<io::Subscriber<Message>> subscribe(io::Bus& bus, web::LiveState& live,
                                                   const std::string& channel, Decode decode,
                                                   Keep keep) {
  return std::make_unique<io::Subscriber<Message>>(
      bus, channel,
      [decode](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return decode(d, n, c);
      },
      [&live, keep](const Message& m, const std::string&) { (live.*keep)(m); },
      [&live, channel](const std::string& what) { live.onBadMessage(channel, what); });
}

// The daemon's channels the page shows, each decoded by io's checked decoders into the
// live state; a bad message is counted there and dropped.
struct LiveSubscriptions {
  LiveSubscriptions(io::Bus& bus, web::LiveState& live) {
    const auto tables = [](const std::uint8_t* d, std::size_t n, const std::string& c) {
      return io::decodeTables(d, n, c);
    };
    labels = subscribe<io::LabelImageMessage>(
        bus, live, kLabels,
        [](const std::uint8_t* d, std::size_t n, const std::string& c) {
          return io::decodeLabelImage(d, n, c);
        },
        &web::LiveState::onLabels);
    frame_tables =
        subscribe<io::TablesMessage>(bus, live, kTables, tables, &web::LiveState::onTables);
    table_map =
        subscribe<io::TablesMessage>(bus, live, kTableMap, tables, &web::LiveState::onTables);
    semantic_map = subscribe<io::SemanticMapMessage>(
        bus, live, kSemanticMap,
        [](const std::uint8_t* d, std::size_t n, const std::string& c) {
          return io::decodeSemanticMap(d, n, c);
        },
        &web::LiveState::onSemanticMap);
    objects = subscribe<io::ObjectsMessage>(
        bus, live, kObjects,
        [](const std::uint8_t* d, std::size_t n, const std::string& c) {
          return io::decodeObjects(d, n, c);
        },
        &web::LiveState::onObjects);
    find_results = subscribe<io::FindResultMessage>(
        bus, live, kFindResult,
        [](const std::uint8_t* d, std::size_t n, const std::string& c) {
          return io::decodeFindResult(d, n, c);
        },
        &web::LiveState::onFindResult);
    status = subscribe<findmug_lcm::status_t>(
        bus, live, kStatus,
        [](const std::uint8_t* d, std::size_t n, const std::string& c) {
          return io::decodeMessage<findmug_lcm::status_t>(d, n, c);
        },
        &web::LiveState::onStatus);
  }
  std::unique_ptr<io::Subscriber<io::LabelImageMessage>> labels;
  std::unique_ptr<io::Subscriber<io::TablesMessage>> frame_tables, table_map;
  std::unique_ptr<io::Subscriber<io::SemanticMapMessage>> semantic_map;
  std::unique_ptr<io::Subscriber<io::ObjectsMessage>> objects;
  std::unique_ptr<io::Subscriber<io::FindResultMessage>> find_results;
  std::unique_ptr<io::Subscriber<findmug_lcm::status_t>> status;
};

}  // namespace

int main(int argc, char** argv) {
  WebFlags flags;
  auto app = cli::makeApp(kProgram,
                          "Serves a local web page showing findmugd live: labels over the "
                          "camera image, tables and search positions, the table map, status");
  addFlags(*app, flags);
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  if (flags.config.help_settings) {
    Config core;
    web::WebConfig web;
    SettingsSchema schema;
    bindCoreSettings(schema, core);
    schema.bind(web::webSettings(), web);
    std::cout << cli::settingsHelp(schema);
    return 0;
  }

  web::WebConfig config;
  web::ServerOptions options;
  try {
    options = serverOptions(flags, config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 2;
  }

  clients::installStopHandlers();  // before any thread (the bus's, the server's) starts
  const std::shared_ptr<io::Bus> bus = clients::openBus(flags.url, kProgram, flags.suffix);
  if (!bus) return 1;
  // The page's requests to findmugd (Save this frame, reload after an install) go out on
  // the same bus; Bus::publish may be called from the server's threads.
  options.send_command = [&bus](const io::CommandMessage& command) {
    const auto bytes = io::encodeMessage(io::encodeCommand(command));
    if (!bus->publish(kCommand, bytes.data(), bytes.size())) {
      throw Error(kCommand + ": the LCM bus refused the command");
    }
  };
  const std::unique_ptr<web::RetrainJobs> retrain = retrainJobs(config, flags.config, options);
  options.retrain = retrain.get();
  web::LiveState live(config.history_s);
  std::unique_ptr<web::WebServer> server;
  try {
    server = std::make_unique<web::WebServer>(options, live);
    server->bind();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 1;
  }
  const LiveSubscriptions subscriptions(*bus, live);

  std::thread http([&] { server->serve(); });
  const auto stop_server = clients::stopSignals().onStop([&] { server->stop(); });
  std::fprintf(stderr,
               "%s: serving http://%s:%d/ ; listening on %s, %s, %s, %s, %s, %s and %s (%s)\n",
               kProgram, config.bind.c_str(), server->port(), kLabels.c_str(), kTables.c_str(),
               kTableMap.c_str(), kSemanticMap.c_str(), kObjects.c_str(), kFindResult.c_str(),
               kStatus.c_str(), bus->describe().c_str());
  // This thread owns the bus. At the end of a replayed log the page stays up, showing
  // the last state, until a stop signal.
  int code = clients::receiveLoop(*bus, kProgram, [] { return false; });
  live.onBusEnded(code == 0 ? "ended" : "failed");
  while (!clients::stopSignals().waitFor(std::chrono::milliseconds(500))) {
  }
  server->stop();
  http.join();
  return code;
}
