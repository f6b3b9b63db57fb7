// The Retrain page's server side; see retrain.hpp.
// The project's headers (Eigen) before httplib.h: the <resolv.h> it pulls in defines a
// macro _res, a parameter name inside Eigen.
#include "retrain.hpp"

#include <fcntl.h>
#include <httplib.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>

#include "findmug/common/error.hpp"
#include "web_http.hpp"
#include "web_server.hpp"

extern char** environ;

namespace findmug::web {

namespace fs = std::filesystem;

namespace {

// KEY=VALUE with a key of letters, digits, '_' and '.', a value without control characters.
bool validSetting(const std::string& s) {
  const auto eq = s.find('=');
  if (eq == std::string::npos || eq == 0 || s.size() > 300) return false;
  for (std::size_t i = 0; i < eq; ++i) {
    const char c = s[i];
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.')) return false;
  }
  for (std::size_t i = eq + 1; i < s.size(); ++i) {
    const auto u = static_cast<unsigned char>(s[i]);
    if (u < 0x20 || u == 0x7f) return false;
  }
  return true;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

RetrainJobs::RetrainJobs(RetrainOptions options) : options_(std::move(options)) {}

RetrainJobs::~RetrainJobs() {
  cancel();
  if (reader_.joinable()) reader_.join();
}

bool RetrainJobs::running() const {
  std::lock_guard lock(mutex_);
  return state_ == "running";
}

void RetrainJobs::start(const std::string& tool, const std::vector<fs::path>& folders,
                        const std::vector<std::string>& sets) {
  if (tool != "train" && tool != "eval") throw Error("tool must be train or eval");
  if (folders.empty()) throw Error("choose at least one dataset folder");
  for (const auto& s : sets) {
    if (!validSetting(s)) throw Error("'" + s.substr(0, 60) + "' is not KEY=VALUE");
  }
  std::lock_guard lock(mutex_);
  if (state_ == "running") throw Error("a job is running");
  if (reader_.joinable()) reader_.join();  // the last job's reader has finished
  ++job_number_;
  job_dir_ = options_.jobs_dir / ("job-" + std::to_string(getpid()) + "-" +
                                  std::to_string(job_number_));
  std::error_code ec;
  fs::create_directories(job_dir_, ec);
  if (ec) throw Error(job_dir_.string() + ": cannot create (" + ec.message() + ")");

  std::vector<std::string> args = {tool == "train" ? options_.train_program
                                                   : options_.eval_program};
  for (const auto& f : folders) {
    args.push_back("--data");
    args.push_back(f.string());
  }
  if (tool == "train") {
    args.push_back("--out");
    args.push_back((job_dir_ / "model.fmf").string());
  } else {
    args.push_back("--folds");
    args.push_back(std::to_string(options_.folds));
    args.push_back("--json");
    args.push_back((job_dir_ / "eval.json").string());
  }
  args.insert(args.end(), options_.config_args.begin(), options_.config_args.end());
  for (const auto& s : sets) {
    args.push_back("--set");
    args.push_back(s);
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw Error(std::string("pipe: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  // The child gets the default signal mask and handlers, not findmug-web's blocked set.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none, all;
  sigemptyset(&none);
  sigfillset(&all);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &all);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, argv[0], &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    throw Error("cannot run " + args[0] + ": " + std::strerror(rc));
  }
  pid_ = pid;
  tool_ = tool;
  state_ = "running";
  exit_code_ = 0;
  cancel_requested_ = false;
  trained_model_.clear();
  output_ = "$";
  for (const auto& a : args) output_ += " " + a;
  output_ += "\n";
  output_dropped_ = 0;
  const int fd = fds[0];
  reader_ = std::thread([this, fd] {
    readOutput(fd);
    waitChild();
  });
}

void RetrainJobs::readOutput(int fd) {
  char buffer[4096];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    std::lock_guard lock(mutex_);
    output_.append(buffer, static_cast<std::size_t>(n));
    if (output_.size() > options_.max_output_bytes) {
      const std::size_t cut = output_.size() - options_.max_output_bytes;
      output_.erase(0, cut);
      output_dropped_ += cut;
    }
  }
  close(fd);
}

void RetrainJobs::waitChild() {
  pid_t pid;
  {
    std::lock_guard lock(mutex_);
    pid = pid_;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  std::lock_guard lock(mutex_);
  pid_ = -1;
  exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  state_ = cancel_requested_ ? "cancelled" : ok ? "succeeded" : "failed";
  if (ok && tool_ == "train" && fs::exists(job_dir_ / "model.fmf")) {
    trained_model_ = job_dir_ / "model.fmf";
  }
}

bool RetrainJobs::cancel() {
  std::lock_guard lock(mutex_);
  if (state_ != "running" || pid_ <= 0) return false;
  cancel_requested_ = true;
  kill(pid_, SIGTERM);
  return true;
}

nlohmann::json RetrainJobs::job(std::size_t offset) const {
  std::lock_guard lock(mutex_);
  nlohmann::json out = {{"state", state_},     {"tool", tool_},
                        {"job", job_number_},  {"exit_code", exit_code_},
                        {"next_offset", output_dropped_ + output_.size()}};
  const std::size_t from = offset > output_dropped_ ? offset - output_dropped_ : 0;
  out["output"] = from < output_.size() ? output_.substr(from) : std::string();
  out["model"] = trained_model_.empty() ? nlohmann::json(nullptr)
                                        : nlohmann::json(trained_model_.string());
  out["can_install"] = !trained_model_.empty() && !options_.install_path.empty();
  out["report"] = nullptr;
  if (state_ == "succeeded" && tool_ == "eval" && fs::exists(job_dir_ / "eval.json")) {
    const auto report = nlohmann::json::parse(readText(job_dir_ / "eval.json"), nullptr, false);
    if (!report.is_discarded()) out["report"] = report;
  }
  return out;
}

fs::path RetrainJobs::install() {
  fs::path model;
  {
    std::lock_guard lock(mutex_);
    model = trained_model_;
  }
  if (options_.install_path.empty()) throw Error("no install path (web.install_path)");
  if (model.empty()) throw Error("no trained model yet: train first");
  const fs::path tmp = options_.install_path.string() + ".new";
  std::error_code ec;
  fs::copy_file(model, tmp, fs::copy_options::overwrite_existing, ec);
  if (ec) throw Error(tmp.string() + ": cannot write (" + ec.message() + ")");
  // On disk before the rename: a crash leaves the old model or the whole new one.
  const int fd = open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    fsync(fd);
    close(fd);
  }
  fs::rename(tmp, options_.install_path, ec);
  if (ec) throw Error(options_.install_path.string() + ": cannot replace (" + ec.message() + ")");
  return options_.install_path;
}

void addRetrainRoutes(httplib::Server& server, RetrainJobs& jobs,
                      const std::vector<fs::path>& roots, SendCommand send) {
  server.Post("/api/retrain/start", [&jobs, roots](const httplib::Request& req,
                                                   httplib::Response& res) {
    auto parsed = jsonObjectBody(req.body, res);
    if (!parsed) return;
    nlohmann::json body = std::move(*parsed);
    if (!body.contains("tool") || !body["tool"].is_string() || !body.contains("folders") ||
        !body["folders"].is_array()) {
      return fail(res, 400, "\"tool\" (train or eval) and \"folders\" (an array) are needed");
    }
    std::vector<fs::path> folders;
    for (const auto& f : body["folders"]) {
      if (!f.is_object() || !f.contains("root") || !f["root"].is_number_unsigned()) {
        return fail(res, 400, "each folder is {\"root\": INDEX, \"path\": \"...\"}");
      }
      const auto root = f["root"].get<std::size_t>();
      if (root >= roots.size()) return fail(res, 400, "no data folder " + std::to_string(root));
      const std::string path = f.contains("path") && f["path"].is_string()
                                   ? f["path"].get<std::string>()
                                   : std::string();
      if (path.empty()) {
        folders.push_back(roots[root]);
        continue;
      }
      const ResolvedPath dir = resolveInside(roots[root], path);
      if (dir.status != 200) return fail(res, dir.status, dir.error);
      if (!fs::is_directory(dir.path)) return fail(res, 400, path + ": not a folder");
      folders.push_back(dir.path);
    }
    std::vector<std::string> sets;
    if (body.contains("set")) {
      if (!body["set"].is_array()) return fail(res, 400, "\"set\" must be an array of strings");
      for (const auto& s : body["set"]) {
        if (!s.is_string()) return fail(res, 400, "\"set\" must be an array of strings");
        sets.push_back(s.get<std::string>());
      }
    }
    if (jobs.running()) return fail(res, 409, "a job is running: wait for it or cancel it");
    try {
      jobs.start(body["tool"].get<std::string>(), folders, sets);
    } catch (const Error& e) {
      return fail(res, jobs.running() ? 409 : 400, e.what());
    }
    sendJson(res, jobs.job(0));
  });
  server.Get("/api/retrain/job", [&jobs](const httplib::Request& req, httplib::Response& res) {
    std::size_t offset = 0;
    const std::string text = req.get_param_value("offset");
    if (!text.empty()) {
      if (text.size() > 12 || text.find_first_not_of("0123456789") != std::string::npos) {
        return fail(res, 400, "offset must be a byte count");
      }
      offset = static_cast<std::size_t>(std::stoull(text));
    }
    sendJson(res, jobs.job(offset));
  });
  server.Post("/api/retrain/cancel", [&jobs](const httplib::Request&, httplib::Response& res) {
    if (!jobs.cancel()) return fail(res, 404, "no job is running");
    sendJson(res, {{"cancelled", true}});
  });
  server.Post("/api/retrain/install", [&jobs, send](const httplib::Request&,
                                                    httplib::Response& res) {
    if (jobs.options().install_path.empty()) {
      return fail(res, 503, "no install path configured (web.install_path)");
    }
    if (!send) return fail(res, 503, "findmug-web has no LCM bus to ask for the reload");
    fs::path installed;
    try {
      installed = jobs.install();
    } catch (const Error& e) {
      return fail(res, 409, e.what());
    }
    io::CommandMessage command;
    command.utime = static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                                   std::chrono::system_clock::now().time_since_epoch())
                                                   .count());
    command.request_id = nextRequestId();
    command.command = "reload_model";
    try {
      send(command);
    } catch (const Error& e) {
      return fail(res, 503, std::string("installed, but the reload was not sent: ") + e.what());
    }
    sendJson(res, {{"installed", installed.string()}, {"request_id", command.request_id}});
  });
}

}  // namespace findmug::web
