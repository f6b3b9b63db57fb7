// web_http.hpp — the small helpers findmug-web's endpoints share (web_server.cpp, the
// Label page's tools label_tools.cpp, command_routes.cpp, retrain.cpp): error and JSON
// answers, JSON request bodies, frame names, file times.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace httplib {
struct Response;
}

namespace findmug::web {

// The Content-Type of every JSON answer. cpp-httplib (Debian's 0.11, built with Brotli)
// compresses a response whose type is exactly "application/json" with Brotli at its
// default quality 11 whenever the browser accepts br: at the live page's 10 updates a
// second that was three quarters of findmug-web's CPU (docs/measurements/web.md). The
// page is read over loopback or the robot's LAN, where the bytes cost nothing, so JSON
// goes uncompressed: the charset parameter (which RFC 8259 allows and JSON readers
// ignore) is not the exact type httplib compresses. WebAccess.JsonAnswersAreNotCompressed
// fails if a library update starts compressing it again.
inline constexpr const char* kJsonContentType = "application/json; charset=utf-8";

// Answers `status` with {"error": message}; the reason also goes into a header for the
// request log (the body may be compressed by then).
void fail(httplib::Response& res, int status, const std::string& message);
// A request body that must be a JSON object: the object, or nothing after answering 400
// ("request body is not JSON: ..." / "request body must be a JSON object").
std::optional<nlohmann::json> jsonObjectBody(const std::string& body, httplib::Response& res);
// Answers `body` as JSON, not to be cached.
void sendJson(httplib::Response& res, const nlohmann::json& body);
// A frame name of a dataset folder: the file stem of rgb/NAME.png (letters, digits, _ - .).
bool validFrameName(const std::string& name);
// The file's modification time in nanoseconds (0 when it cannot be read).
std::int64_t mtimeNs(const std::filesystem::path& path);
// The current time, ISO 8601 UTC ("2026-11-28T17:00:00Z").
std::string utcNow();

}  // namespace findmug::web
