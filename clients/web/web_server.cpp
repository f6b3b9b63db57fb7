// findmug-web's HTTP server; see web_server.hpp.
#include "web_server.hpp"

#include <httplib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>
#include <system_error>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "web_config.hpp"
#include "web_http.hpp"

namespace findmug::web {

namespace fs = std::filesystem;

namespace {

constexpr const char* kTokenCookie = "findmug_token";

// The reason also goes into a header for the log: the body may be compressed by then.
constexpr const char* kErrorHeader = "X-Findmug-Error";

// Compares without an early exit, so that the time taken does not tell how much matched
// (the length may show; the token's length is not the secret).
bool sameToken(const std::string& given, const std::string& token) {
  if (given.size() != token.size()) return false;
  unsigned diff = 0;
  for (std::size_t i = 0; i < token.size(); ++i) {
    diff |= static_cast<unsigned char>(given[i]) ^ static_cast<unsigned char>(token[i]);
  }
  return diff == 0;
}

std::string cookieValue(const std::string& header, const std::string& name) {
  std::size_t pos = 0;
  while (pos < header.size()) {
    std::size_t end = header.find(';', pos);
    if (end == std::string::npos) end = header.size();
    std::string part = header.substr(pos, end - pos);
    const auto first = part.find_first_not_of(' ');
    if (first != std::string::npos) part = part.substr(first);
    if (part.rfind(name + "=", 0) == 0) return part.substr(name.size() + 1);
    pos = end + 1;
  }
  return {};
}

std::string contentType(const std::string& name) {
  const auto ends = [&](const char* ext) {
    const std::string e(ext);
    return name.size() >= e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".png")) return "image/png";
  if (ends(".jpg") || ends(".jpeg")) return "image/jpeg";
  if (ends(".json")) return kJsonContentType;
  if (ends(".csv") || ends(".txt") || ends(".yaml")) return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

std::string readWholeFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot read");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

bool insideRoot(const fs::path& root, const fs::path& path) {
  auto r = root.begin();
  auto p = path.begin();
  for (; r != root.end(); ++r, ++p) {
    if (p == path.end() || *r != *p) return false;
  }
  return true;
}

}  // namespace

void fail(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  std::string header = message.substr(0, 300);  // printable only: it may echo the request
  for (char& c : header) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  res.set_header(kErrorHeader, header);
  res.set_content(nlohmann::json{{"error", message}}.dump(), kJsonContentType);
}

std::optional<nlohmann::json> jsonObjectBody(const std::string& body, httplib::Response& res) {
  nlohmann::json parsed;
  try {
    parsed = nlohmann::json::parse(body);
  } catch (const std::exception& e) {
    fail(res, 400, std::string("request body is not JSON: ") + e.what());
    return std::nullopt;
  }
  if (!parsed.is_object()) {
    fail(res, 400, "request body must be a JSON object");
    return std::nullopt;
  }
  return parsed;
}

void sendJson(httplib::Response& res, const nlohmann::json& body) {
  res.set_header("Cache-Control", "no-store");
  res.set_content(body.dump(), kJsonContentType);
}

bool validFrameName(const std::string& name) {
  if (name.empty() || name.size() > 200 || name == "." || name == "..") return false;
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) return false;
  }
  return name.find("..") == std::string::npos;
}

std::int64_t mtimeNs(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return 0;
  return static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

ResolvedPath resolveInside(const fs::path& root, const std::string& relative, bool may_be_missing) {
  ResolvedPath out;
  auto refuse = [&](int status, std::string why) {
    out.status = status;
    out.error = std::move(why);
    return out;
  };
  if (relative.size() > 4096) return refuse(400, "path too long");
  for (char c : relative) {
    if (static_cast<unsigned char>(c) < 0x20 || c == '\\') {
      return refuse(400, "path holds a control character or a backslash");
    }
  }
  if (!relative.empty() && relative.front() == '/') {
    return refuse(400, "path '" + relative + "' is absolute; give it relative to the data folder");
  }
  fs::path joined = root;
  if (!relative.empty()) {
    std::size_t pos = 0;
    while (pos <= relative.size()) {
      std::size_t end = relative.find('/', pos);
      if (end == std::string::npos) end = relative.size();
      const std::string part = relative.substr(pos, end - pos);
      if (part == "..") return refuse(400, "path '" + relative + "' holds '..'");
      if (part.empty() || part == ".") {
        return refuse(400, "path '" + relative + "' holds an empty or '.' component");
      }
      joined /= part;
      pos = end + 1;
    }
  }
  std::error_code ec;
  fs::path canonical;
  if (may_be_missing && !fs::exists(fs::symlink_status(joined, ec))) {
    const fs::path parent = fs::canonical(joined.parent_path(), ec);
    if (ec) return refuse(404, "folder of '" + relative + "' not found");
    canonical = parent / joined.filename();
  } else {
    canonical = fs::canonical(joined, ec);
    if (ec) return refuse(404, "'" + relative + "' not found");
  }
  if (!insideRoot(root, canonical)) {
    return refuse(403, "'" + relative + "' leads out of the data folder (symlink)");
  }
  out.path = canonical;
  return out;
}

WebServer::WebServer(ServerOptions options, LiveState& live)
    : options_(std::move(options)),
      label_frames_(std::make_unique<LabelFrames>(options_.segmenter, options_.model,
                                                  options_.model_name, options_.nyu_rotations)),
      live_(live),
      server_(std::make_unique<httplib::Server>()) {
  for (const auto& dir : options_.data_dirs) {
    std::error_code ec;
    const fs::path canonical = fs::canonical(dir, ec);
    if (ec || !fs::is_directory(canonical)) {
      throw Error("--data " + dir.string() + ": not a folder");
    }
    roots_.push_back(canonical);
  }
  loadStaticFiles();
  routes();
}

WebServer::~WebServer() { stop(); }

void WebServer::loadStaticFiles() {
  std::error_code ec;
  if (!fs::is_regular_file(options_.static_dir / "index.html", ec)) {
    throw Error("static folder " + options_.static_dir.string() + ": no index.html");
  }
  for (const auto& entry : fs::directory_iterator(options_.static_dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    if (!validFrameName(name)) continue;
    static_files_[name] = readWholeFile(entry.path());
  }
}

void WebServer::routes() {
  httplib::Server& s = *server_;
  s.set_payload_max_length(options_.max_body_bytes);
  s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    return admit(req, res) ? httplib::Server::HandlerResponse::Unhandled
                           : httplib::Server::HandlerResponse::Handled;
  });
  addErrorReporting(s);
  addPageRoutes(s);
  // Requests to the daemon (command_routes.hpp).
  addCommandRoutes(s, options_.send_command);
  if (options_.retrain) addRetrainRoutes(s, *options_.retrain, roots_, options_.send_command);
  addLiveRoutes(s);
  addDataRoutes(s);
  addLabelRoutes(s);
}

// Whom and what this server serves: the token (header, query or cookie) or, without one,
// this machine only; a body within the limit. False after the refusal is answered.
bool WebServer::admit(const httplib::Request& req, httplib::Response& res) const {
  if (options_.token) {
    std::string given;
    bool from_query = false;
    const std::string auth = req.get_header_value("Authorization");
    if (auth.rfind("Bearer ", 0) == 0) {
      given = auth.substr(7);
    } else if (req.has_param("token")) {
      given = req.get_param_value("token");
      from_query = true;
    } else {
      given = cookieValue(req.get_header_value("Cookie"), kTokenCookie);
    }
    if (given.empty()) {
      fail(res, 401, "this server needs its access token (see findmug-web --help)");
      return false;
    }
    if (!sameToken(given, *options_.token)) {
      fail(res, 403, "wrong access token");
      return false;
    }
    if (from_query) {
      res.set_header("Set-Cookie", std::string(kTokenCookie) + "=" + given +
                                       "; Path=/; HttpOnly; SameSite=Strict");
    }
  } else if (!isLoopbackAddress(req.remote_addr)) {
    fail(res, 403, "served to this machine only (no token configured)");
    return false;
  }
  if (req.has_header("Content-Length")) {
    const std::string length = req.get_header_value("Content-Length");
    std::size_t n = 0;
    bool digits = !length.empty() && length.size() <= 19;
    for (char c : length) {
      if (c < '0' || c > '9') digits = false;
    }
    if (!digits) {
      fail(res, 400, "bad Content-Length '" + length + "'");
      res.set_header("Connection", "close");
      return false;
    }
    n = static_cast<std::size_t>(std::stoull(length));
    if (n > options_.max_body_bytes) {
      fail(res, 413,
           "request body of " + length + " bytes is over the limit of " +
               std::to_string(options_.max_body_bytes));
      res.set_header("Connection", "close");
      return false;
    }
  }
  return true;
}

void WebServer::addErrorReporting(httplib::Server& s) {
  s.set_logger([](const httplib::Request& req, const httplib::Response& res) {
    if (res.status < 400) return;
    const std::string why = res.get_header_value(kErrorHeader);
    std::fprintf(stderr, "findmug-web: %d for %s %s from %s: %s\n", res.status, req.method.c_str(),
                 req.path.c_str(), req.remote_addr.c_str(), why.c_str());
  });
  s.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;  // a handler said why already
    if (res.status == 413) {
      fail(res, 413, "request body over the limit");
    } else if (res.status == 404) {
      fail(res, 404, "no such page or endpoint");
    } else {
      fail(res, res.status, "bad request");
    }
  });
  s.set_exception_handler(
      [](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        try {
          if (ep) std::rethrow_exception(ep);
        } catch (const std::exception& e) {
          fail(res, 500, e.what());
          return;
        } catch (...) {
        }
        fail(res, 500, "internal error");
      });
}

void WebServer::serveStatic(const std::string& name, httplib::Response& res) const {
  const auto it = static_files_.find(name);
  if (it == static_files_.end()) {
    fail(res, 404, "no file '" + name + "'");
    return;
  }
  res.set_header("Cache-Control", "no-cache");
  res.set_content(it->second, contentType(name));
}

void WebServer::addPageRoutes(httplib::Server& s) {
  // --- the page's files ---
  s.Get("/", [this](const httplib::Request&, httplib::Response& res) {
    serveStatic("index.html", res);
  });
  s.Get("/label", [this](const httplib::Request&, httplib::Response& res) {
    serveStatic("label.html", res);
  });
  s.Get(R"(/static/([^/]+))", [this](const httplib::Request& req, httplib::Response& res) {
    serveStatic(req.matches[1], res);
  });
}

void WebServer::addLiveRoutes(httplib::Server& s) {
  // --- live ---
  s.Get("/api/live", [this](const httplib::Request&, httplib::Response& res) {
    sendJson(res, live_.liveJson());
  });
  s.Get("/api/labels.bin", [this](const httplib::Request&, httplib::Response& res) {
    const auto labels = live_.labels();
    if (!labels) return fail(res, 404, "no label image received yet");
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Findmug-Seq", std::to_string(labels->seq));
    res.set_header("X-Findmug-Width", std::to_string(labels->width));
    res.set_header("X-Findmug-Height", std::to_string(labels->height));
    res.set_content(reinterpret_cast<const char*>(labels->labels->data()), labels->labels->size(),
                    "application/octet-stream");
  });
  // The semantic map from above: label plane then confidence plane (live_state.hpp).
  s.Get("/api/semantic_map.bin", [this](const httplib::Request&, httplib::Response& res) {
    const auto map = live_.semanticMap();
    if (!map) return fail(res, 404, "no semantic map received yet (findmugd: daemon.semantic_map)");
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Findmug-Seq", std::to_string(map->seq));
    res.set_header("X-Findmug-Width", std::to_string(map->width));
    res.set_header("X-Findmug-Height", std::to_string(map->height));
    res.set_content(reinterpret_cast<const char*>(map->bytes->data()), map->bytes->size(),
                    "application/octet-stream");
  });
  s.Get("/api/color.jpg", [this](const httplib::Request&, httplib::Response& res) {
    const auto color = live_.colorJpeg();
    if (!color) {
      return fail(res, 404,
                  "the latest label image carries no colour image (findmugd: "
                  "daemon.publish_color)");
    }
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Findmug-Seq", std::to_string(color->first));
    res.set_content(reinterpret_cast<const char*>(color->second->data()), color->second->size(),
                    "image/jpeg");
  });
}

const fs::path* WebServer::rootOf(const httplib::Request& req, httplib::Response& res) const {
  return rootAt(req.get_param_value("root"), res);
}

const fs::path* WebServer::rootAt(const std::string& text, httplib::Response& res) const {
  std::size_t index = 0;
  bool ok = !text.empty() && text.size() < 6;
  for (char c : text) ok = ok && c >= '0' && c <= '9';
  if (ok) index = static_cast<std::size_t>(std::stoul(text));
  if (!ok || index >= roots_.size()) {
    fail(res, 400,
         "root must be the index of a data folder (0.." + std::to_string(roots_.size()) +
             " exclusive), got '" + text + "'");
    return nullptr;
  }
  return &roots_[index];
}

std::optional<std::string> WebServer::frameOf(const httplib::Request& req, httplib::Response& res,
                                              std::size_t& root_index) const {
  const fs::path* root = rootOf(req, res);
  if (!root) return std::nullopt;
  root_index = static_cast<std::size_t>(root - roots_.data());
  const std::string frame = req.get_param_value("frame");
  if (!validFrameName(frame)) {
    fail(res, 400, "frame '" + frame + "' is not a frame name (letters, digits, _ - .)");
    return std::nullopt;
  }
  const ResolvedPath rgb = resolveInside(*root, "rgb/" + frame + ".png");
  if (rgb.status != 200) {
    fail(res, rgb.status, rgb.error);
    return std::nullopt;
  }
  return frame;
}

void WebServer::addDataRoutes(httplib::Server& s) {
  // --- data folders ---
  s.Get("/api/data", [this](const httplib::Request&, httplib::Response& res) {
    nlohmann::json folders = nlohmann::json::array();
    for (std::size_t i = 0; i < roots_.size(); ++i) {
      folders.push_back(
          {{"root", i}, {"name", roots_[i].filename().string()}, {"path", roots_[i].string()}});
    }
    sendJson(res, {{"folders", folders}});
  });
  s.Get("/api/data/list", [this](const httplib::Request& req, httplib::Response& res) {
    const fs::path* root = rootOf(req, res);
    if (!root) return;
    const ResolvedPath dir = resolveInside(*root, req.get_param_value("path"));
    if (dir.status != 200) return fail(res, dir.status, dir.error);
    if (!fs::is_directory(dir.path)) return fail(res, 400, "not a folder");
    nlohmann::json entries = nlohmann::json::array();
    std::vector<std::pair<std::string, bool>> names;
    for (const auto& e : fs::directory_iterator(dir.path)) {
      names.emplace_back(e.path().filename().string(), e.is_directory());
    }
    std::sort(names.begin(), names.end());
    for (const auto& [name, is_dir] : names) entries.push_back({{"name", name}, {"dir", is_dir}});
    sendJson(res, {{"entries", entries}});
  });
  s.Get("/api/data/file", [this](const httplib::Request& req, httplib::Response& res) {
    const fs::path* root = rootOf(req, res);
    if (!root) return;
    const ResolvedPath file = resolveInside(*root, req.get_param_value("path"));
    if (file.status != 200) return fail(res, file.status, file.error);
    if (!fs::is_regular_file(file.path)) return fail(res, 400, "not a file");
    res.set_header("X-Findmug-Mtime-Ns", std::to_string(mtimeNs(file.path)));
    res.set_content(readWholeFile(file.path), contentType(file.path.filename().string()));
  });
}

void WebServer::addLabelRoutes(httplib::Server& s) {
  // --- the Label page: a dataset folder's frames, their oversegmentation, their labels ---
  // Frames of a dataset folder: rgb/NAME.png with depth/NAME.png (labelled or not yet).
  s.Get("/api/label/frames", [this](const httplib::Request& req, httplib::Response& res) {
    const fs::path* root = rootOf(req, res);
    if (!root) return;
    const ResolvedPath rgb = resolveInside(*root, "rgb");
    if (rgb.status != 200) return fail(res, rgb.status, "not a dataset folder: " + rgb.error);
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(rgb.path)) {
      const fs::path name = e.path().filename();
      if (name.extension() != ".png" || !validFrameName(name.stem().string())) continue;
      if (fs::exists(*root / "depth" / name)) names.push_back(name.stem().string());
    }
    std::sort(names.begin(), names.end());
    nlohmann::json frames = nlohmann::json::array();
    for (const auto& name : names) {
      frames.push_back(
          {{"name", name}, {"labelled", fs::exists(*root / "label8" / (name + ".png"))}});
    }
    sendJson(res, {{"frames", frames}});
  });
  s.Get("/api/label/frame", [this](const httplib::Request& req, httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frameOf(req, res, root);
    if (!frame) return;
    const auto patches = patchesOf(root, *frame);
    const fs::path label = roots_[root] / "label8" / (*frame + ".png");
    nlohmann::json body = {{"frame", *frame},
                           {"width", patches->width},
                           {"height", patches->height},
                           {"patches", patches->segments},
                           {"label_mtime_ns", nullptr}};
    // Nanoseconds as text: a JavaScript number keeps only 53 bits.
    if (fs::exists(label)) body["label_mtime_ns"] = std::to_string(mtimeNs(label));
    sendJson(res, body);
  });
  // The patch of every pixel, uint16 little-endian, 65535 = in no patch.
  s.Get("/api/label/patches.bin", [this](const httplib::Request& req, httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frameOf(req, res, root);
    if (!frame) return;
    const auto patches = patchesOf(root, *frame);
    std::string bytes(patches->patch.size() * 2, '\0');
    for (std::size_t i = 0; i < patches->patch.size(); ++i) {
      bytes[2 * i] = static_cast<char>(patches->patch[i] & 0xFF);
      bytes[2 * i + 1] = static_cast<char>(patches->patch[i] >> 8);
    }
    res.set_header("Cache-Control", "no-store");
    res.set_content(bytes, "application/octet-stream");
  });
  // The frame's label8/ file as one byte per pixel (404 when it has none yet).
  s.Get("/api/label/labels.bin", [this](const httplib::Request& req, httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frameOf(req, res, root);
    if (!frame) return;
    const ResolvedPath label = resolveInside(roots_[root], "label8/" + *frame + ".png");
    if (label.status != 200) return fail(res, label.status, label.error);
    const Image<std::uint8_t> image = readPng8(label.path.string());
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Findmug-Mtime-Ns", std::to_string(mtimeNs(label.path)));
    res.set_content(reinterpret_cast<const char*>(image.pixels.data()), image.pixels.size(),
                    "application/octet-stream");
  });

  s.Post("/api/label",
         [this](const httplib::Request& req, httplib::Response& res) { saveLabels(req, res); });
  addLabelToolRoutes(s, *label_frames_, roots_,
                     [this](const httplib::Request& req, httplib::Response& res,
                            std::size_t& root_index) { return frameOf(req, res, root_index); });
}

// POST /api/label: {"root": K, "frame": NAME, "width": W, "height": H,
//   "runs": [[id, count], ...] (row-major, ids 0..7 or 255), "author": "...",
//   "base_mtime_ns": "N" (text, as /api/label/frame gives it) or null}
//   -> DATA/label8/NAME.png (+ NAME.json: who, when).
// An existing label file whose mtime is not base_mtime_ns (newer work) is not
// overwritten: 409.
void WebServer::saveLabels(const httplib::Request& req, httplib::Response& res) {
  auto parsed = jsonObjectBody(req.body, res);
  if (!parsed) return;
  nlohmann::json body = std::move(*parsed);
  for (const char* key : {"root", "frame", "width", "height", "runs", "author"}) {
    if (!body.contains(key)) return fail(res, 400, std::string("missing field '") + key + "'");
  }
  if (!body["root"].is_number_unsigned() || !body["frame"].is_string() ||
      !body["width"].is_number_unsigned() || !body["height"].is_number_unsigned() ||
      !body["runs"].is_array() || !body["author"].is_string()) {
    return fail(res, 400,
                "fields root, width, height must be unsigned numbers, frame and "
                "author strings, runs an array");
  }
  const fs::path* root = rootAt(std::to_string(body["root"].get<std::uint64_t>()), res);
  if (!root) return;
  const std::string frame = body["frame"].get<std::string>();
  if (!validFrameName(frame)) {
    return fail(res, 400, "frame '" + frame + "' is not a frame name (letters, digits, _ - .)");
  }
  const ResolvedPath rgb = resolveInside(*root, "rgb/" + frame + ".png");
  if (rgb.status != 200) return fail(res, rgb.status, rgb.error);
  const std::uint64_t width = body["width"].get<std::uint64_t>();
  const std::uint64_t height = body["height"].get<std::uint64_t>();
  if (width == 0 || height == 0 || width > 4096 || height > 4096) {
    return fail(res, 400, "width and height must be 1..4096");
  }
  const Image<Rgb8> image = readPngRgb(rgb.path.string());
  if (static_cast<std::uint64_t>(image.width) != width ||
      static_cast<std::uint64_t>(image.height) != height) {
    return fail(res, 400,
                "labels are " + std::to_string(width) + "x" + std::to_string(height) +
                    " but the frame is " + std::to_string(image.width) + "x" +
                    std::to_string(image.height));
  }
  Image<std::uint8_t> labels;
  labels.width = image.width;
  labels.height = image.height;
  try {
    labels.pixels = labelsFromRuns(body["runs"], width * height);
  } catch (const Error& e) {
    return fail(res, 400, e.what());
  }
  const std::string author = body["author"].get<std::string>();
  if (author.size() > 200) return fail(res, 400, "author longer than 200 characters");
  // label8/ is made on the first save (resolveInside then checks it stays inside).
  if (!fs::exists(fs::symlink_status(*root / "label8"))) fs::create_directory(*root / "label8");
  const ResolvedPath out = resolveInside(*root, "label8/" + frame + ".png", true);
  if (out.status != 200) return fail(res, out.status, out.error);
  if (fs::exists(out.path)) {
    const std::int64_t on_disk = mtimeNs(out.path);
    // base_mtime_ns: what /api/label/frame or the last save said, as text (or a number).
    bool same = false;
    if (body.contains("base_mtime_ns")) {
      const auto& base = body["base_mtime_ns"];
      same = (base.is_string() && base.get<std::string>() == std::to_string(on_disk)) ||
             (base.is_number_integer() && base.get<std::int64_t>() == on_disk);
    }
    if (!same) {
      return fail(res, 409,
                  "label8/" + frame +
                      ".png was written since this page read it "
                      "(mtime " +
                      std::to_string(on_disk) + "): not overwritten");
    }
  }
  // Written next to its place and renamed over it: a crash leaves the old file whole.
  const fs::path tmp = out.path.parent_path() / ("." + frame + ".png.tmp");
  writePng8(tmp.string(), labels);
  fs::rename(tmp, out.path);
  const nlohmann::json sidecar = {
      {"author", author}, {"saved_utc", utcNow()}, {"tool", "findmug-web"}, {"frame", frame}};
  const fs::path sidecar_path = out.path.parent_path() / (frame + ".json");
  {
    std::ofstream side(out.path.parent_path() / ("." + frame + ".json.tmp"));
    side << sidecar.dump(2) << "\n";
    if (!side) throw Error(sidecar_path.string() + ": cannot write");
  }
  fs::rename(out.path.parent_path() / ("." + frame + ".json.tmp"), sidecar_path);
  fs::remove(draftPath(*root, frame));  // saved: the draft's work is in the file
  sendJson(res, {{"saved", "label8/" + frame + ".png"},
                 {"mtime_ns", std::to_string(mtimeNs(out.path))}});
}

std::shared_ptr<const LabelFrame> WebServer::patchesOf(std::size_t root, const std::string& frame) {
  return label_frames_->of(roots_[root], root, frame);
}

void WebServer::bind() {
  if (options_.port == 0) {
    port_ = server_->bind_to_any_port(options_.bind.c_str());
    if (port_ < 0) throw Error("cannot listen on " + options_.bind + " (any port)");
  } else {
    if (!server_->bind_to_port(options_.bind.c_str(), options_.port)) {
      throw Error("cannot listen on " + options_.bind + ":" + std::to_string(options_.port));
    }
    port_ = options_.port;
  }
}

void WebServer::serve() { server_->listen_after_bind(); }

void WebServer::stop() {
  if (server_) server_->stop();
}

}  // namespace findmug::web
