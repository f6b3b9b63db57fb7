// findmug-web's requests to findmugd; see command_routes.hpp.
// The project's headers (Eigen) before httplib.h: the <resolv.h> it pulls in defines a
// macro _res, a parameter name inside Eigen.
#include "command_routes.hpp"

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <nlohmann/json.hpp>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/objects/object_model.hpp"
#include "web_http.hpp"

namespace findmug::web {

namespace {

std::uint64_t nowUs() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

// The command as the daemon would take it, or why not.
std::string checkArgument(const std::string& command, const std::string& argument) {
  if (command == "reload_model") {
    return argument.empty() ? "" : "reload_model takes no argument";
  }
  if (command == "save_frame") {
    return argument.find_first_of(",\"") == std::string::npos
               ? ""
               : "the save_frame note may not hold a comma or a quote";
  }
  if (command == "teach") {
    try {
      (void)io::parseTeachArgument(argument, "argument");
      return "";
    } catch (const Error& e) {
      return e.what();
    }
  }
  if (command == "find") {
    try {
      validateObjectModelName(argument);
      return "";
    } catch (const Error& e) {
      return std::string("find: ") + e.what();
    }
  }
  return "command must be save_frame, reload_model, teach or find, not '" +
         command.substr(0, 40) + "'";
}

}  // namespace

std::int64_t nextRequestId() {
  static std::atomic<std::int64_t> next{static_cast<std::int64_t>(nowUs() / 1000)};
  return next.fetch_add(1);
}

void addCommandRoutes(httplib::Server& server, SendCommand send) {
  server.Post("/api/command", [send](const httplib::Request& req, httplib::Response& res) {
    if (!send) return fail(res, 503, "findmug-web has no LCM bus to publish commands on");
    auto parsed = jsonObjectBody(req.body, res);
    if (!parsed) return;
    nlohmann::json body = std::move(*parsed);
    if (!body.contains("command") || !body["command"].is_string()) {
      return fail(res, 400, "\"command\" (a string) is missing");
    }
    const auto argument_field = body.find("argument");
    if (argument_field != body.end() && !argument_field->is_string()) {
      return fail(res, 400, "\"argument\" must be a string");
    }
    io::CommandMessage command;
    command.utime = nowUs();
    command.command = body["command"].get<std::string>();
    command.argument = argument_field != body.end() ? argument_field->get<std::string>() : "";
    if (const std::string why = checkArgument(command.command, command.argument); !why.empty()) {
      return fail(res, 400, why);
    }
    command.request_id = nextRequestId();
    try {
      (void)io::encodeCommand(command);  // the daemon's field rules
      send(command);
    } catch (const Error& e) {
      return fail(res, 400, e.what());
    }
    res.set_header("Cache-Control", "no-store");
    res.set_content(nlohmann::json{{"request_id", command.request_id}}.dump(), kJsonContentType);
  });
}

}  // namespace findmug::web
