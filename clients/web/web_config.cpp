// findmug-web's settings; see web_config.hpp.
#include "web_config.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <fstream>

#include "findmug/common/error.hpp"

namespace findmug::web {

const SettingsTable<WebConfig>& webSettings() {
  static const SettingsTable<WebConfig> table = [] {
    using W = WebConfig;
    SettingsTable<W> t("web");
    t.add(textSetting<W>(
        "web.bind", [](W& w) -> std::string& { return w.bind; },
        [](const std::string& v) {
          return v.empty() || v.find_first_of(" \t/") != std::string::npos
                     ? std::string("an IP address or host name")
                     : std::string();
        },
        "address to listen on; other than 127.0.0.1/::1/localhost needs web.token_file"));
    t.add(integerSetting<W, int>(
        "web.port", [](W& w) -> int& { return w.port; }, 1, 65535, "TCP port"));
    t.add(textSetting<W>(
        "web.token_file", [](W& w) -> std::string& { return w.token_file; }, {},
        "file holding the access token (required off loopback)"));
    t.add(integerSetting<W, long long>(
        "web.max_body_bytes", [](W& w) -> long long& { return w.max_body_bytes; }, 1024,
        256LL * 1024 * 1024, "largest request body; 413 above it"));
    t.add(numberSetting<W, double>(
        "web.history_s", [](W& w) -> double& { return w.history_s; }, 10, 3600,
        "how far back the status plots reach"));
    t.add(textSetting<W>(
        "web.static_dir", [](W& w) -> std::string& { return w.static_dir; }, {},
        "folder of the page's HTML/JS/CSS; empty = the installed one"));
    t.add(textSetting<W>(
        "web.model_path", [](W& w) -> std::string& { return w.model_path; }, {},
        "model the Label page's prediction comes from; empty = none"));
    t.add(textSetting<W>(
        "web.nyu_rotations", [](W& w) -> std::string& { return w.nyu_rotations; }, {},
        "NYU's camera_rotations_NYU.txt for frames named by NYU index; empty = none"));
    t.add(textSetting<W>(
        "web.train_program", [](W& w) -> std::string& { return w.train_program; }, {},
        "findmug-train to run from the Retrain page (a name on PATH or a path)"));
    t.add(textSetting<W>(
        "web.eval_program", [](W& w) -> std::string& { return w.eval_program; }, {},
        "findmug-eval to run from the Retrain page"));
    t.add(textSetting<W>(
        "web.jobs_dir", [](W& w) -> std::string& { return w.jobs_dir; }, {},
        "where Retrain jobs write models and reports; empty = no Retrain page"));
    t.add(textSetting<W>(
        "web.install_path", [](W& w) -> std::string& { return w.install_path; }, {},
        "Install copies the trained model here (findmugd's daemon.model_path); empty = off"));
    t.add(integerSetting<W, int>(
        "web.retrain_folds", [](W& w) -> int& { return w.retrain_folds; }, 2, 50,
        "findmug-eval --folds on the Retrain page"));
    return t;
  }();
  return table;
}

void registerWebSection() {
  static const bool registered = [] {
    configSections().addSection("web", [](const std::string& key, const std::string& value) {
      webSettings().check(key, value);
    });
    return true;
  }();
  (void)registered;
}

WebConfig resolveWebConfig(const Config& config) {
  WebConfig web;
  for (const auto& [key, value] : config.extra) {
    if (key.rfind("web.", 0) == 0) webSettings().set(web, key, value);
  }
  return web;
}

bool isDefaultLoopback(const std::string& address) {
  return address == "127.0.0.1" || address == "::1" || address == "localhost";
}

bool isLoopbackAddress(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address == "::1" ||
         address.rfind("::ffff:127.", 0) == 0;
}

std::string readTokenFile(const std::filesystem::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw Error(path.string() + ": cannot read the token file");
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%03o", static_cast<unsigned>(st.st_mode & 0777));
    throw Error(path.string() + ": the token file must be readable by its owner only (mode " +
                mode + ")");
  }
  std::ifstream in(path);
  std::string token;
  if (!in || !std::getline(in, token)) throw Error(path.string() + ": cannot read the token file");
  const auto first = token.find_first_not_of(" \t\r");
  const auto last = token.find_last_not_of(" \t\r");
  token = first == std::string::npos ? "" : token.substr(first, last - first + 1);
  if (token.size() < 16) {
    throw Error(path.string() + ": the token is " + std::to_string(token.size()) +
                " characters long, at least 16 are needed");
  }
  for (char c : token) {
    if (c <= ' ' || c > '~') throw Error(path.string() + ": the token holds a blank or control character");
  }
  return token;
}

}  // namespace findmug::web
