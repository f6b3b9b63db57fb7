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
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"

namespace findmug::cli {

// An app named `program` (used in messages and --version) with --version.
std::unique_ptr<CLI::App> makeApp(const std::string& program, const std::string& description);

// --config FILE and repeatable --set KEY=VALUE.
struct ConfigFlags {
  std::optional<std::string> config_path;
  std::vector<std::string> overrides;  // KEY=VALUE as given
  bool help_settings = false;          // --help-settings: the program prints settingsHelp
};
// Also --help-settings, which the program answers with settingsHelp of its schema.
void addConfigFlags(CLI::App& app, ConfigFlags& flags, const std::string& config_help);
// Reads the --config file (if any), then every --set, through `schema`: the tables the
// program bound get its values, every other table of the shared file
// (acceptSharedFileSettings, program_settings.hpp) checks its section; then the rules
// across keys. Throws findmug::Error naming the file, line or setting that is wrong.
void readSettings(const ConfigFlags& flags, SettingsSchema& schema);
// For a program that uses the core's sections only (findmug-train, findmug-eval): readSettings
// with bindCoreSettings and bindOfflineSettings.
Config configFrom(const ConfigFlags& flags);
// --help-settings: every setting `schema` has bound, and every one of the shared file
// (acceptSharedFileSettings), with its built-in default, range and doc line.
std::string settingsHelp(SettingsSchema& schema);
// The same for the programs on configFrom (the core's and offline sections).
std::string coreSettingsHelp();

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
// version: 0; parse error: 2, message on stderr), nullopt to go on (with
// --help-settings, before any other flag is checked: ConfigFlags::help_settings).
std::optional<int> parse(CLI::App& app, int argc, const char* const* argv);

}  // namespace findmug::cli
