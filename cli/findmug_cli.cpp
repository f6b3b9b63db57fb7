#include "findmug_cli.hpp"

#include <iostream>

#include "findmug/common/numbers.hpp"
#include "findmug/settings/settings.hpp"
#include "program_settings.hpp"
#include "findmug/version.hpp"

namespace findmug::cli {

std::unique_ptr<CLI::App> makeApp(const std::string& program, const std::string& description) {
  auto app = std::make_unique<CLI::App>(description, program);
  app->set_version_flag("--version", program + " " + kVersion);
  // Flags only: a stray word is an error rather than silently ignored.
  app->allow_extras(false);
  app->option_defaults()->always_capture_default();
  return app;
}

void addConfigFlags(CLI::App& app, ConfigFlags& flags, const std::string& config_help) {
  app.add_option_function<std::string>(
         "--config", [&flags](const std::string& path) { flags.config_path = path; }, config_help)
      ->type_name("FILE");
  app.add_option("--set", flags.overrides,
                 "override one setting, e.g. --set mrf.lambda=2 (repeatable; later wins)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false)
      ->check([](const std::string& text) -> std::string {
        const auto eq = text.find('=');
        if (eq == std::string::npos || eq == 0) return "expected KEY=VALUE, got '" + text + "'";
        return {};
      });
  // Stops the parse at once (before the checks of required flags): the program then prints
  // its settings (settingsHelp) and exits.
  app.add_flag_callback(
      "--help-settings",
      [&flags] {
        flags.help_settings = true;
        throw CLI::Success();
      },
      "list every setting: key = built-in default (what a value must be), its doc "
      "line; [model] marks the keys a model records and sets unless given");
}

void readSettings(const ConfigFlags& flags, SettingsSchema& schema) {
  acceptSharedFileSettings(schema);
  if (flags.config_path) schema.readFile(*flags.config_path);
  for (const auto& kv : flags.overrides) schema.applyOverride(kv);
  const std::string origin = flags.config_path ? *flags.config_path : std::string("<flags>");
  schema.validate(flags.config_path && !flags.overrides.empty() ? origin + " + flags" : origin);
}

Config configFrom(const ConfigFlags& flags) {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  readSettings(flags, schema);
  return config;
}

std::string settingsHelp(SettingsSchema& schema) {
  acceptSharedFileSettings(schema);
  return schema.help();
}

std::string coreSettingsHelp() {
  Config config;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  bindOfflineSettings(schema, config);
  return settingsHelp(schema);
}

CLI::Option* addSourceFlag(CLI::App& app, std::string& spec, const std::string& help) {
  return app.add_option("--source", spec, help)->type_name("SPEC");
}

CLI::Option* addLcmUrlFlag(CLI::App& app, std::string& url, const std::string& help) {
  return app.add_option("--lcm-url,--url", url, help)->type_name("URL");
}

CLI::Option* addChannelSuffixFlag(CLI::App& app, std::string& suffix) {
  return app
      .add_option("--channel-suffix", suffix,
                  "appended to every findmug channel name (several daemons on one network)")
      ->type_name("S");
}

CLI::Option* addModelFlag(CLI::App& app, std::string& path, const std::string& help) {
  return app.add_option("--model", path, help)->type_name("FILE");
}

namespace {
CLI::Validator numberAtLeast(double min, bool inclusive) {
  const std::string rule = std::string(inclusive ? ">= " : "> ") + (min == 0 ? "0" : "1");
  return CLI::Validator(
      [min, inclusive, rule](std::string& text) -> std::string {
        const auto value = parseNumber(text);
        if (!value) return "must be a number " + rule + ", got '" + text + "'";
        if (inclusive ? *value >= min : *value > min) return {};
        return "must be " + rule + ", got '" + text + "'";
      },
      "NUMBER " + rule);
}
}  // namespace

CLI::Validator positive() { return numberAtLeast(0, false); }
CLI::Validator nonNegative() { return numberAtLeast(0, true); }

std::optional<int> parse(CLI::App& app, int argc, const char* const* argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return 0;
  } catch (const CLI::CallForVersion&) {
    std::cout << app.version() << "\n";
    return 0;
  } catch (const CLI::Success&) {
    return std::nullopt;  // --help-settings (addConfigFlags): the program lists its settings
  } catch (const CLI::ParseError& e) {
    std::cerr << app.get_name() << ": " << e.what() << " (see --help)\n";
    return 2;
  }
  return std::nullopt;
}

}  // namespace findmug::cli
