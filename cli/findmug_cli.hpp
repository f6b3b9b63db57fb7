// findmug_cli.hpp — the one command-line layer of the findmug programs (CLI11).
//
// Every program builds its flags on a CLI::App made by makeApp(), which gives it
// --help and --version, and takes the flags that mean the same thing in several
// programs from the helpers below, so that they are spelled the same everywhere:
//
//   --config FILE        YAML config            --set KEY=VALUE   one setting (repeatable)
//   --source SPEC        frame source spec      --lcm-url URL     LCM provider (alias --url)
//   --model FILE         forest model           --channel-suffix  suffix of every channel name
//
// parse() turns CLI11's outcome into an exit code the same way in every program:
// 0 after --help / --version, 2 with "PROGRAM: message (see --help)" for a bad flag.
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "findmug/settings/config.hpp"

namespace findmug::cli {

// An app named `program` (used in messages and --version) with --version.
std::unique_ptr<CLI::App> makeApp(const std::string& program, const std::string& description);

// The config file is shared by the project's programs. These are the sections
// that belong to one program and that every other one must accept unread
// (findmug-train reads findmugd.yaml): the daemon's `daemon:` and `check:`,
// the clients' `clients:`, findmug-web's `web:`. The owner registers its section with its keys
// (findmugd: daemon/daemon_config.cpp); others know only the name. The core's
// own sections (SegmenterConfig and `table_map:`) are not listed here.
inline constexpr std::array<const char*, 4> kProjectSections = {"daemon", "check", "clients",
                                                                 "web"};
// Registers kProjectSections by name in findmug::configSections(). Idempotent.
void declareProjectSections();

// --config FILE and repeatable --set KEY=VALUE.
struct ConfigFlags {
  std::optional<std::string> config_path;
  std::vector<std::string> overrides;  // KEY=VALUE as given
};
void addConfigFlags(CLI::App& app, ConfigFlags& flags, const std::string& config_help);
// The config those flags give: the --config file (or the defaults) with every --set on top.
// Declares the project's sections first (declareProjectSections).
// Throws findmug::Error naming the file or the setting that is wrong.
Config configFrom(const ConfigFlags& flags);

CLI::Option* addSourceFlag(CLI::App& app, std::string& spec, const std::string& help);
// --lcm-url with --url as an alias (findmug-grab and the test tools have used --url).
CLI::Option* addLcmUrlFlag(CLI::App& app, std::string& url, const std::string& help);
CLI::Option* addChannelSuffixFlag(CLI::App& app, std::string& suffix);
CLI::Option* addModelFlag(CLI::App& app, std::string& path, const std::string& help);

// Number checks with short messages ("must be > 0, got '-1'"); CLI11's own
// PositiveNumber/NonNegativeNumber print the whole range of a double.
CLI::Validator positive();
CLI::Validator nonNegative();

// Parses argv. Returns an exit code when the program should stop now (help,
// version: 0; parse error: 2, message on stderr), nullopt to go on.
std::optional<int> parse(CLI::App& app, int argc, const char* const* argv);

}  // namespace findmug::cli
