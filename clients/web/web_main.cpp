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
constexpr const char* kProgram = "findmug-web";
}

int main(int argc, char** argv) {
  using namespace findmug;
  std::string url, suffix, bind, token_file, static_dir, model_path, nyu_rotations;
  std::vector<std::string> data_dirs;
  int port = 0;
  cli::ConfigFlags config_flags;
  auto app = cli::makeApp(kProgram,
                          "Serves a local web page showing findmugd live: labels over the "
                          "camera image, tables and search positions, the table map, status");
  cli::addConfigFlags(*app, config_flags, "YAML config (its web: section)");
  cli::addLcmUrlFlag(*app, url, "LCM provider (default: LCM_DEFAULT_URL or udpm default)");
  cli::addChannelSuffixFlag(*app, suffix);
  app->add_option("--port", port, "TCP port (default web.port, 8088)")
      ->check(CLI::Range(1, 65535));
  app->add_option("--bind", bind,
                  "address to listen on (default web.bind, 127.0.0.1); any other than "
                  "127.0.0.1/::1/localhost needs --token-file")
      ->type_name("ADDR");
  app->add_option("--token-file", token_file,
                  "file with the access token (owner-only permissions); required on every "
                  "request when given")
      ->type_name("FILE");
  app->add_option("--data", data_dirs, "data folders the page may read and label (repeatable)")
      ->type_name("DIR");
  app->add_option("--static-dir", static_dir, "the page's files (default web.static_dir, or "
                                              FINDMUG_WEB_STATIC_DIR ")")
      ->type_name("DIR");
  app->add_option("--model", model_path,
                  "model the Label page's prediction comes from (default web.model_path)")
      ->type_name("FILE");
  app->add_option("--nyu-rotations", nyu_rotations,
                  "NYU's camera_rotations_NYU.txt (default web.nyu_rotations)")
      ->type_name("FILE");
  if (auto code = cli::parse(*app, argc, argv)) return *code;

  web::WebConfig config;
  // Base names: the bus applies --channel-suffix (io::SuffixedBus).
  const std::string labels_channel(io::kLabelsChannel), tables_channel(io::kTablesChannel),
      map_channel(io::kTableMapChannel), semantic_channel(io::kSemanticMapChannel),
      status_channel(io::kStatusChannel), command_channel(io::kCommandChannel),
      objects_channel(io::kObjectsChannel), find_channel(io::kFindResultChannel);
  web::ServerOptions options;
  try {
    Config loaded;  // the segmenter's sections (the Label page's prediction) and web:
    SettingsSchema schema;
    bindCoreSettings(schema, loaded);
    schema.bind(web::webSettings(), config);
    cli::readSettings(config_flags, schema);
    if (!bind.empty()) config.bind = bind;
    if (port != 0) config.port = port;
    if (!token_file.empty()) config.token_file = token_file;
    if (!static_dir.empty()) config.static_dir = static_dir;
    if (!model_path.empty()) config.model_path = model_path;
    if (!nyu_rotations.empty()) config.nyu_rotations = nyu_rotations;
    io::checkChannelSuffix(suffix);
    options.bind = config.bind;
    options.port = config.port;
    options.max_body_bytes = static_cast<std::size_t>(config.max_body_bytes);
    options.static_dir = config.static_dir.empty() ? FINDMUG_WEB_STATIC_DIR : config.static_dir;
    for (const auto& d : data_dirs) options.data_dirs.emplace_back(d);
    options.segmenter = loaded.segmenter;
    if (!config.model_path.empty()) {
      options.model = std::make_shared<const RandomForest>(RandomForest::load(config.model_path));
      options.model_name =
          std::filesystem::path(config.model_path).filename().string() + ":" + options.model->id();
    }
    if (!config.nyu_rotations.empty()) options.nyu_rotations = config.nyu_rotations;
    if (!config.token_file.empty()) {
      options.token = web::readTokenFile(config.token_file);
    } else if (!web::isDefaultLoopback(config.bind)) {
      throw Error("listening on " + config.bind +
                  " needs an access token: give --token-file (or web.token_file)");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 2;
  }

  clients::installStopHandlers();  // before any thread (the bus's, the server's) starts
  const std::shared_ptr<io::Bus> bus = clients::openBus(url, kProgram, suffix);
  if (!bus) return 1;
  // The page's requests to findmugd (Save this frame, reload after an install) go out on
  // the same bus; Bus::publish may be called from the server's threads.
  options.send_command = [&bus, command_channel](const io::CommandMessage& command) {
    const auto bytes = io::encodeMessage(io::encodeCommand(command));
    if (!bus->publish(command_channel, bytes.data(), bytes.size())) {
      throw Error(command_channel + ": the LCM bus refused the command");
    }
  };
  std::unique_ptr<web::RetrainJobs> retrain;
  if (!config.jobs_dir.empty()) {
    web::RetrainOptions r;
    r.train_program = config.train_program;
    r.eval_program = config.eval_program;
    r.jobs_dir = config.jobs_dir;
    r.install_path = config.install_path;
    r.folds = config.retrain_folds;
    // The tools read the same config findmug-web was given (the daemon's settings).
    if (config_flags.config_path) r.config_args = {"--config", *config_flags.config_path};
    for (const auto& o : config_flags.overrides) {
      r.config_args.push_back("--set");
      r.config_args.push_back(o);
    }
    // NYU frames get their gravity from NYU's rotations in training as on the Label page.
    if (!config.nyu_rotations.empty()) {
      r.config_args.insert(r.config_args.end(), {"--nyu-rotations", config.nyu_rotations});
    }
    retrain = std::make_unique<web::RetrainJobs>(std::move(r));
    options.retrain = retrain.get();
  }
  web::LiveState live(config.history_s);
  std::unique_ptr<web::WebServer> server;
  try {
    server = std::make_unique<web::WebServer>(options, live);
    server->bind();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 1;
  }

  auto bad = [&live](const std::string& channel) {
    return [&live, channel](const std::string& what) { live.onBadMessage(channel, what); };
  };
  auto decode_tables = [](const std::uint8_t* d, std::size_t n, const std::string& c) {
    return io::decodeTables(d, n, c);
  };
  io::Subscriber<io::LabelImageMessage> labels(
      *bus, labels_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeLabelImage(d, n, c);
      },
      [&](const io::LabelImageMessage& m, const std::string&) { live.onLabels(m); },
      bad(labels_channel));
  io::Subscriber<io::TablesMessage> tables(
      *bus, tables_channel, decode_tables,
      [&](const io::TablesMessage& m, const std::string&) { live.onTables(m); },
      bad(tables_channel));
  io::Subscriber<io::TablesMessage> table_map(
      *bus, map_channel, decode_tables,
      [&](const io::TablesMessage& m, const std::string&) { live.onTables(m); },
      bad(map_channel));
  io::Subscriber<io::SemanticMapMessage> semantic_map(
      *bus, semantic_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeSemanticMap(d, n, c);
      },
      [&](const io::SemanticMapMessage& m, const std::string&) { live.onSemanticMap(m); },
      bad(semantic_channel));
  io::Subscriber<io::ObjectsMessage> objects(
      *bus, objects_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeObjects(d, n, c);
      },
      [&](const io::ObjectsMessage& m, const std::string&) { live.onObjects(m); },
      bad(objects_channel));
  io::Subscriber<io::FindResultMessage> find_results(
      *bus, find_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeFindResult(d, n, c);
      },
      [&](const io::FindResultMessage& m, const std::string&) { live.onFindResult(m); },
      bad(find_channel));
  io::Subscriber<findmug_lcm::status_t> status(
      *bus, status_channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeMessage<findmug_lcm::status_t>(d, n, c);
      },
      [&](const findmug_lcm::status_t& m, const std::string&) { live.onStatus(m); },
      bad(status_channel));

  std::thread http([&] { server->serve(); });
  const auto stop_server = clients::stopSignals().onStop([&] { server->stop(); });
  std::fprintf(stderr,
               "%s: serving http://%s:%d/ ; listening on %s, %s, %s, %s, %s, %s and %s (%s)\n",
               kProgram, config.bind.c_str(), server->port(), labels_channel.c_str(),
               tables_channel.c_str(), map_channel.c_str(), semantic_channel.c_str(),
               objects_channel.c_str(), find_channel.c_str(), status_channel.c_str(),
               bus->describe().c_str());
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
