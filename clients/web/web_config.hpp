// web_config.hpp — findmug-web's settings (the `web:` section of a findmug config file)
// and what its command line adds to them.
//
// The section's struct and table (WebConfig, webSettings) are in cli/program_settings.hpp,
// where the other programs sharing the file check its keys too; findmug-web binds it
// (SettingsSchema::bind) and reads its values straight into a WebConfig.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "program_settings.hpp"

namespace findmug::web {

// True for the addresses that reach this machine only through its loopback interface
// and are served without a token: 127.0.0.1, ::1 and "localhost".
bool isDefaultLoopback(const std::string& address);
// True for any address of the loopback range (127.0.0.0/8, ::1, ::ffff:127.x.y.z).
bool isLoopbackAddress(const std::string& address);

// The token in `path`: its first line without surrounding blanks. Throws findmug::Error
// when the file cannot be read, the token is shorter than 16 characters, or the file
// can be read or written by others than its owner (group/other permission bits).
std::string readTokenFile(const std::filesystem::path& path);

}  // namespace findmug::web
