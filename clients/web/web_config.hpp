// web_config.hpp — findmug-web's settings (the `web:` section of a findmug config file)
// and what its command line adds to them.
//
// The section belongs to findmug-web: it registers it with its keys (every key checked
// while the file is read), and the other programs accept it unread (cli::kProjectSections).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"

namespace findmug::web {

struct WebConfig {
  // Address to listen on. 127.0.0.1 (or ::1, localhost) serves this machine only and
  // needs no token; any other address requires token_file.
  std::string bind = "127.0.0.1";
  int port = 8088;
  // File holding the access token (first line, at least 16 characters); "" = none.
  std::string token_file;
  // Largest request body accepted, bytes (413 above it, on every endpoint).
  long long max_body_bytes = 4LL * 1024 * 1024;
  // How far back the status plots reach, seconds.
  double history_s = 300.0;
  // Where the page's HTML/JS/CSS are ("" = the installed folder).
  std::string static_dir;
  // The model whose prediction the Label page starts from ("" = none); its cloud.*,
  // normals.*, overseg.* and features.* settings must be the config's, as for findmugd.
  std::string model_path;
  // NYU's camera_rotations_NYU.txt, for ground.source=gravity on frames named by their
  // NYU index ("" = none).
  std::string nyu_rotations;
  // The Retrain page (retrain.hpp): the tools it runs, where its jobs write their model
  // and report ("" = the page is off), the model file findmugd loads (daemon.model_path;
  // "" = no Install), findmug-eval's folds.
  std::string train_program = "findmug-train";
  std::string eval_program = "findmug-eval";
  std::string jobs_dir;
  std::string install_path;
  int retrain_folds = 5;
};

const SettingsTable<WebConfig>& webSettings();
// Registers the `web` section with its checks (idempotent). Call before reading a config.
void registerWebSection();
// The `web.*` values of `config` on top of the defaults; throws findmug::Error naming the key.
WebConfig resolveWebConfig(const Config& config);

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
