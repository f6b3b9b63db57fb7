// retrain.hpp — the Retrain page's server side: findmug-train / findmug-eval run as a
// child process on chosen dataset folders, one job at a time, output kept for the page,
// and "Install": the trained model copied over findmugd's model file in one rename, then
// reload_model sent (command_routes.hpp).
//
//   POST /api/retrain/start   {"tool": "train" | "eval", "folders": [{"root": I, "path": P}],
//                              "set": ["key=value", ...]}   409 while a job runs
//   GET  /api/retrain/job?offset=N  the job: state (idle, running, succeeded, failed,
//                              cancelled), the tool's output from byte N, the exit code, and
//                              for eval the tool's JSON report (figures and confusion)
//   POST /api/retrain/cancel  SIGTERM to the running job (404 when none runs)
//   POST /api/retrain/install copy the last trained model to web.install_path (409 without
//                              one, 503 without an install path), then reload_model ->
//                              {"installed": PATH, "request_id": N}
// Folders are data folders (--data, by index) or folders inside them (resolveInside: no
// "..", no symlink escapes). "set" entries are KEY=VALUE settings (a key of letters,
// digits, '_' and '.'), passed as --set to the tool after the web's own --config/--set.
// The tools get no shell: argv only.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "command_routes.hpp"

namespace httplib {
class Server;
}

namespace findmug::web {

struct RetrainOptions {
  std::string train_program = "findmug-train";
  std::string eval_program = "findmug-eval";
  std::vector<std::string> config_args;  // --config FILE / --set K=V / --nyu-rotations F of findmug-web
  std::filesystem::path jobs_dir;        // each job's model / report; empty: the page is off
  std::filesystem::path install_path;    // findmugd's daemon.model_path; empty: no Install
  int folds = 5;                          // findmug-eval --folds
  std::size_t max_output_bytes = 1u << 20;  // the tool's output kept (its tail)
};

class RetrainJobs {
 public:
  explicit RetrainJobs(RetrainOptions options);
  ~RetrainJobs();  // cancels a running job and waits for it
  RetrainJobs(const RetrainJobs&) = delete;
  RetrainJobs& operator=(const RetrainJobs&) = delete;

  // Starts the tool; throws findmug::Error when it cannot (a job runs: the caller answers
  // 409; checked by running()).
  void start(const std::string& tool, const std::vector<std::filesystem::path>& folders,
             const std::vector<std::string>& sets);
  bool running() const;
  bool cancel();  // false when no job runs
  nlohmann::json job(std::size_t offset) const;
  // Copies the last trained model over install_path (temporary file, fsync, rename);
  // returns the path. Throws findmug::Error naming what is missing.
  std::filesystem::path install();
  const RetrainOptions& options() const { return options_; }

 private:
  void readOutput(int fd);
  void waitChild();

  RetrainOptions options_;
  mutable std::mutex mutex_;  // guards everything below
  std::string state_ = "idle", tool_;
  std::string output_;
  std::size_t output_dropped_ = 0;  // bytes cut from the front of output_
  int exit_code_ = 0;
  pid_t pid_ = -1;
  int job_number_ = 0;
  std::filesystem::path job_dir_, trained_model_;
  bool cancel_requested_ = false;
  std::thread reader_;
};

void addRetrainRoutes(httplib::Server& server, RetrainJobs& jobs,
                      const std::vector<std::filesystem::path>& roots, SendCommand send);

}  // namespace findmug::web
