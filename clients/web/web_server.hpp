// web_server.hpp — findmug-web's HTTP server: the page's files, the live state as JSON
// and pixels, the data folders, and the access rules every request goes through.
//
// Access rules (checked before any handler runs, every request):
//   * a token, when one is configured (required by findmug-web off the default loopback
//     address): "Authorization: Bearer TOKEN", the cookie findmug_token, or ?token=
//     (which also sets the cookie, so that the page's own files load); missing 401,
//     wrong 403;
//   * without a token, only loopback peers (127.0.0.0/8, ::1) are served (403);
//   * a body over max_body_bytes: 413, on every endpoint and method;
//   * paths name a file inside one of the data folders (--data): relative, no "..",
//     and still inside after symlinks are resolved (403 otherwise);
//   * a JSON body that does not parse or lacks a field: 400.
// Every answer of 400 or above is logged on stderr with the peer, request and reason.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "command_routes.hpp"
#include "findmug/settings/config.hpp"
#include "label_tools.hpp"
#include "live_state.hpp"
#include "retrain.hpp"

namespace httplib {
class Server;
}

namespace findmug::web {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8088;                   // 0: any free port (see WebServer::port())
  std::optional<std::string> token;  // required on every request when set
  std::size_t max_body_bytes = 4u << 20;
  std::filesystem::path static_dir;  // index.html, *.js, *.css
  std::vector<std::filesystem::path> data_dirs;
  // The oversegmentation the Label page shows is made with these settings (cloud,
  // normals, oversegmentation.*: with a model, the ones it records, configForModel).
  SegmenterConfig segmenter;
  // The model whose prediction the Label page starts from (null: none), its name for
  // the page, and NYU's gravity rotations for frames named by their NYU index.
  std::shared_ptr<const RandomForest> model;
  std::string model_name;
  std::optional<std::string> nyu_rotations;
  // Publishes a command to findmugd (command_routes.hpp); empty: POST /api/command is 503.
  SendCommand send_command;
  // The Retrain page's jobs (retrain.hpp; not owned); nullptr: its endpoints are absent.
  RetrainJobs* retrain = nullptr;
};

// A path inside one of the data folders, or why not (HTTP status and message).
struct ResolvedPath {
  std::filesystem::path path;  // canonical, when status == 200
  int status = 200;
  std::string error;
};
// `relative` inside data folder `root` (canonical). Refused: absolute paths, "..", ".",
// empty components, backslashes, control characters (400); a path that leaves the folder
// through a symlink (403); a missing file (404) unless `may_be_missing` (then its parent
// must exist inside the folder).
ResolvedPath resolveInside(const std::filesystem::path& root, const std::string& relative,
                           bool may_be_missing = false);

class WebServer {
 public:
  // Throws findmug::Error when the static folder or a data folder is unusable.
  WebServer(ServerOptions options, LiveState& live);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  // Binds (throws findmug::Error naming the address when it cannot), then serves on the
  // calling thread until stop().
  void bind();
  void serve();
  void stop();
  int port() const { return port_; }

 private:
  // The endpoints, by group; routes() installs them all.
  void routes();
  bool admit(const httplib::Request& req, httplib::Response& res) const;
  static void addErrorReporting(httplib::Server& s);
  void addPageRoutes(httplib::Server& s);
  void addLiveRoutes(httplib::Server& s);
  void addDataRoutes(httplib::Server& s);
  void addLabelRoutes(httplib::Server& s);
  void serveStatic(const std::string& name, httplib::Response& res) const;
  // The data folder a request's "root" names (or a given index as text), or nullptr after
  // a 400 answer; the frame a request names in it, or nullopt after an error answer.
  const std::filesystem::path* rootOf(const httplib::Request& req, httplib::Response& res) const;
  const std::filesystem::path* rootAt(const std::string& text, httplib::Response& res) const;
  std::optional<std::string> frameOf(const httplib::Request& req, httplib::Response& res,
                                     std::size_t& root_index) const;
  // POST /api/label (the Label page's save).
  void saveLabels(const httplib::Request& req, httplib::Response& res);
  void loadStaticFiles();

  // The oversegmentation of a dataset frame for the Label page (cached, last few).
  std::shared_ptr<const LabelFrame> patchesOf(std::size_t root, const std::string& frame);

  ServerOptions options_;
  std::unique_ptr<LabelFrames> label_frames_;
  LiveState& live_;
  std::vector<std::filesystem::path> roots_;         // canonical data folders
  std::map<std::string, std::string> static_files_;  // name -> content
  std::unique_ptr<httplib::Server> server_;
  int port_ = 0;
};

}  // namespace findmug::web
