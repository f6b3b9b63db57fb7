// web_http.hpp — the small helpers findmug-web's endpoints share (web_server.cpp and the
// Label page's tools, label_tools.cpp): error and JSON answers, frame names, file times.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace httplib {
struct Response;
}

namespace findmug::web {

// Answers `status` with {"error": message}; the reason also goes into a header for the
// request log (the body may be compressed by then).
void fail(httplib::Response& res, int status, const std::string& message);
// Answers `body` as JSON, not to be cached.
void sendJson(httplib::Response& res, const nlohmann::json& body);
// A frame name of a dataset folder: the file stem of rgb/NAME.png (letters, digits, _ - .).
bool validFrameName(const std::string& name);
// The file's modification time in nanoseconds (0 when it cannot be read).
std::int64_t mtimeNs(const std::filesystem::path& path);
// The current time, ISO 8601 UTC ("2026-11-28T17:00:00Z").
std::string utcNow();

}  // namespace findmug::web
