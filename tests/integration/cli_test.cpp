// The shared command-line layer (cli/findmug_cli.hpp) and findmugd's flags on it:
// --help/--version/bad flags give the same exit codes everywhere, number checks name the
// flag and value, and findmugd keeps --set and its shortcuts in command-line order.
// findmug-train and findmug-eval are run as programs to check their flags on the layer.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/version.hpp"
#include "findmug_cli.hpp"
#include "program_settings.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

std::optional<int> parseArgs(CLI::App& app, std::vector<const char*> args) {
  args.insert(args.begin(), "prog");
  return cli::parse(app, static_cast<int>(args.size()), args.data());
}

TEST(Cli, HelpVersionAndBadFlagsStopWithTheirExitCodes) {
  int count = 0;
  std::string url;
  auto app = cli::makeApp("findmug-x", "test program");
  cli::addLcmUrlFlag(*app, url, "where");
  app->add_option("--count", count)->check(cli::positive());
  testing::internal::CaptureStdout();
  EXPECT_EQ(parseArgs(*app, {"--version"}), 0);
  EXPECT_EQ(testing::internal::GetCapturedStdout(), std::string("findmug-x ") + kVersion + "\n");

  auto help_app = cli::makeApp("findmug-x", "test program");
  testing::internal::CaptureStdout();
  EXPECT_EQ(parseArgs(*help_app, {"--help"}), 0);
  EXPECT_NE(testing::internal::GetCapturedStdout().find("--version"), std::string::npos);

  auto bad_app = cli::makeApp("findmug-x", "test program");
  bad_app->add_option("--count", count)->check(cli::positive());
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(*bad_app, {"--count", "0"}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("findmug-x: --count: must be > 0, got '0' (see --help)"), std::string::npos)
      << err;

  auto url_app = cli::makeApp("findmug-x", "test program");
  cli::addLcmUrlFlag(*url_app, url, "where");
  EXPECT_EQ(parseArgs(*url_app, {"--url", "memq://"}), std::nullopt);  // the old name still works
  EXPECT_EQ(url, "memq://");
}

TEST(Cli, FindmugdKeepsOverridesInCommandLineOrder) {
  const daemon::CommandLine cl = daemon::parseCommandLine(
      {"--set", "mrf.lambda=1", "--workers", "2", "--set", "daemon.workers=3", "--model", "m.fmf",
       "--set", "mrf.lambda=4", "--check"});
  EXPECT_EQ(cl.overrides,
            (std::vector<std::string>{"mrf.lambda=1", "daemon.workers=2", "daemon.workers=3",
                                      "daemon.model_path=m.fmf", "mrf.lambda=4"}));
  EXPECT_TRUE(cl.check);
  EXPECT_FALSE(cl.check_config);
  EXPECT_TRUE(daemon::parseCommandLine({"--version"}).version);
  EXPECT_TRUE(daemon::parseCommandLine({"--help"}).help);
  try {
    daemon::parseCommandLine({"--workers"});
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--workers"), std::string::npos) << e.what();
  }
}

struct ProgramRun {
  int exit_code = -1;
  std::string out, err;
};

// Runs `command` with stdout and stderr captured apart (stderr into a temp file).
ProgramRun runProgram(const std::string& command) {
  ProgramRun r;
  char err_path[] = "/tmp/findmug_cli_test_XXXXXX";
  const int fd = mkstemp(err_path);
  if (fd < 0) return r;
  close(fd);
  FILE* pipe = popen((command + " 2>" + err_path).c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), pipe)) r.out += buf.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err_path);
  std::stringstream s;
  s << in.rdbuf();
  r.err = s.str();
  std::remove(err_path);
  return r;
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Cli, TrainAndEvalGiveHelpAndVersion) {
  for (const auto& [exe, name] : {std::pair{std::string(FINDMUG_TRAIN_EXE), "findmug-train"},
                                  std::pair{std::string(FINDMUG_EVAL_EXE), "findmug-eval"}}) {
    ProgramRun r = runProgram(exe + " --version");
    EXPECT_EQ(r.exit_code, 0) << name;
    EXPECT_EQ(r.out, std::string(name) + " " + kVersion + "\n");

    r = runProgram(exe + " --help");
    EXPECT_EQ(r.exit_code, 0) << name;
    for (const char* flag : {"--data", "--mat", "--out", "--config", "--set", "--nyu894-csv",
                             "--no-nyu-border", "--nyu-rotations", "--version"}) {
      EXPECT_TRUE(has(r.out, flag)) << name << " --help lacks " << flag << ":\n" << r.out;
    }
  }
  const ProgramRun eval = runProgram(std::string(FINDMUG_EVAL_EXE) + " --help");
  for (const char* flag : {"--folds", "--model", "--json", "--sweep", "--train-extra"}) {
    EXPECT_TRUE(has(eval.out, flag)) << "findmug-eval --help lacks " << flag;
  }
}

// --help-settings of the tools on the core's settings: every setting of the shared file with
// its built-in default, what a value must be and its doc line; it reads no data.
TEST(Cli, TrainAndEvalListTheirSettings) {
  for (const std::string& exe : {std::string(FINDMUG_TRAIN_EXE), std::string(FINDMUG_EVAL_EXE)}) {
    const ProgramRun r = runProgram(exe + " --help-settings");
    EXPECT_EQ(r.exit_code, 0) << exe << r.err;
    for (const char* line : {"forest.num_trees = 8  (an integer in [1, 1000])\n    trees",
                             "training.degraded_copies = 0  (an integer in [0, 8])\n    ",
                             "features.regions = false  (true or false) [model]\n    region"}) {
      EXPECT_TRUE(has(r.out, line)) << exe << " --help-settings lacks " << line;
    }
  }
}

TEST(Cli, TrainAndEvalRejectBadFlagsWithCode2NamingThem) {
  const std::string train(FINDMUG_TRAIN_EXE), eval(FINDMUG_EVAL_EXE);
  struct Case {
    std::string command, expected;
  };
  const std::vector<Case> cases = {
      {train + " --data /tmp --out m.fmf --bogus 3", "findmug-train: The following argument"},
      {train + " --data /tmp --out m.fmf --bogus 3", "--bogus"},
      {train + " --data /tmp", "--out is required"},
      {train + " --out m.fmf", "give at least one --data DIR or --mat FILE"},
      {train + " --data /tmp --out m.fmf --set mrf.lambda", "expected KEY=VALUE, got 'mrf.lambda'"},
      {eval + " --data /tmp --bogus 3", "--bogus"},
      {eval + " --data /tmp --folds 1", "--folds: must be an integer >= 2, got '1'"},
      {eval + " --data /tmp --folds five", "--folds: must be an integer >= 2, got 'five'"},
      {eval + " --data /tmp --folds 2.5", "--folds: must be an integer >= 2, got '2.5'"},
      {eval + " --folds 3", "give --data DIR or --mat FILE"},
      {eval + " --data /tmp --folds-by rooms", "--folds-by"},
  };
  for (const auto& c : cases) {
    const ProgramRun r = runProgram(c.command);
    EXPECT_EQ(r.exit_code, 2) << c.command << "\n" << r.err;
    EXPECT_TRUE(has(r.err, c.expected))
        << c.command << "\nexpected: " << c.expected << "\ngot: " << r.err;
  }
}

TEST(Cli, TrainAndEvalReadBothFlagFormsAndLastValueWins) {
  // --name=value works like --name value. --data is repeatable (all folders are read, in
  // order): the run fails on the first folder, which does not exist.
  const ProgramRun r =
      runProgram(std::string(FINDMUG_EVAL_EXE) +
                 " --data /nonexistent/first --data=/nonexistent/second --folds=3");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(has(r.err, "/nonexistent/first")) << r.err;
  EXPECT_FALSE(has(r.err, "/nonexistent/second")) << r.err;
}

// findmug-eval and findmug-train read findmugd's file with the real tables of every
// section in it (cli/program_settings.hpp): the other programs' sections are accepted
// and checked key by key, so a typo in `daemon:` is refused here too, and a section
// no program has is refused naming the setting.
TEST(Cli, EvalAndTrainCheckEverySectionOfTheSharedFile) {
  const std::string dir = ::testing::TempDir();
  const std::string shared = dir + "/cli_test_shared.yaml";
  const std::string daemon_typo = dir + "/cli_test_daemon_typo.yaml";
  const std::string typo = dir + "/cli_test_typo.yaml";
  std::ofstream(shared) << "daemon:\n  workers: 2\ncheck:\n  frames: 3\nweb:\n  port: 9000\n"
                           "table_map:\n  confirm_sightings: 5\nforest:\n  num_trees: 3\n";
  std::ofstream(daemon_typo) << "forest:\n  num_trees: 3\ndaemon:\n  wokers: 2\n";
  std::ofstream(typo) << "forrest:\n  num_trees: 3\n";
  for (const std::string& program : {FINDMUG_EVAL_EXE, FINDMUG_TRAIN_EXE}) {
    const std::string exe =
        program == FINDMUG_TRAIN_EXE ? program + " --out " + dir + "/cli_test.fmf" : program;
    const ProgramRun ok = runProgram(exe + " --config " + shared + " --data /nonexistent/d");
    EXPECT_EQ(ok.exit_code, 1) << ok.err;
    EXPECT_TRUE(has(ok.err, "/nonexistent/d")) << exe << ": " << ok.err;  // got past the config
    const ProgramRun bad_key = runProgram(exe + " --config " + daemon_typo + " --data /nonexistent/d");
    EXPECT_EQ(bad_key.exit_code, 1) << bad_key.err;
    EXPECT_TRUE(has(bad_key.err, daemon_typo + ": line 4: unknown setting 'daemon.wokers' (daemon keys: "))
        << exe << ": " << bad_key.err;
    const ProgramRun bad_flag =
        runProgram(exe + " --config " + shared + " --set daemon.wokers=2 --data /nonexistent/d");
    EXPECT_EQ(bad_flag.exit_code, 1) << bad_flag.err;
    EXPECT_TRUE(has(bad_flag.err, "<flags>: unknown setting 'daemon.wokers'")) << bad_flag.err;
    const ProgramRun bad = runProgram(exe + " --config " + typo + " --data /nonexistent/d");
    EXPECT_EQ(bad.exit_code, 1) << bad.err;
    EXPECT_TRUE(has(bad.err, "unknown setting 'forrest.num_trees': no section 'forrest'"))
        << exe << ": " << bad.err;
  }
}

// readSettings: the tables a program binds get the values, parsed once; every other
// section of the shared file is checked with its real table.
TEST(Cli, ReadSettingsFillsTheBoundStructsAndChecksTheOthers) {
  const std::string path = ::testing::TempDir() + "/cli_test_daemon.yaml";
  std::ofstream(path) << "forest:\n  num_trees: 5\ndaemon:\n  wokers: 2\n";
  cli::ConfigFlags flags;
  flags.config_path = path;
  try {
    (void)cli::configFrom(flags);
    ADD_FAILURE() << "daemon.wokers accepted";
  } catch (const Error& e) {
    EXPECT_TRUE(has(e.what(), path + ": line 4: unknown setting 'daemon.wokers' (daemon keys: "))
        << e.what();
  }
  std::ofstream(path) << "forest:\n  num_trees: 5\ndaemon:\n  workers: 2\n";
  flags.overrides = {"web.port=9000", "forest.num_trees=6"};
  EXPECT_EQ(cli::configFrom(flags).segmenter.forest.num_trees, 6);
  // A program that binds web: gets its value; the daemon's section is still checked.
  Config config;
  web::WebConfig web;
  SettingsSchema schema;
  bindCoreSettings(schema, config);
  schema.bind(web::webSettings(), web);
  cli::readSettings(flags, schema);
  EXPECT_EQ(web.port, 9000);
  EXPECT_EQ(config.segmenter.forest.num_trees, 6);
  flags.overrides = {"web.prot=9000"};
  try {
    cli::readSettings(flags, schema);
    ADD_FAILURE() << "web.prot accepted";
  } catch (const Error& e) {
    EXPECT_TRUE(has(e.what(), "<flags>: unknown setting 'web.prot' (web keys: ")) << e.what();
  }
}

#if defined(FINDMUG_REPLAY_EXE) && defined(FINDMUG_REPLAY_PROBE_EXE) && \
    defined(FINDMUG_SEQUENTIAL_EXE)
TEST(Cli, ReplayHelpersGiveHelpVersionAndNameBadFlags) {
  const std::string replay(FINDMUG_REPLAY_EXE), probe(FINDMUG_REPLAY_PROBE_EXE);
  for (const auto& [exe, name] :
       {std::pair{replay, "findmug-replay"}, std::pair{probe, "findmug-replay-probe"}}) {
    ProgramRun r = runProgram(exe + " --version");
    EXPECT_EQ(r.exit_code, 0) << name;
    EXPECT_EQ(r.out, std::string(name) + " " + kVersion + "\n");
    r = runProgram(exe + " --help");
    EXPECT_EQ(r.exit_code, 0) << name;
    for (const char* flag : {"--lcm-url", "--channel-suffix", "--version"}) {
      EXPECT_TRUE(has(r.out, flag)) << name << " --help lacks " << flag << ":\n" << r.out;
    }
  }
  // findmug-sequential takes findmugd's flags (daemon_config.cpp) and its own name.
  const ProgramRun sequential = runProgram(std::string(FINDMUG_SEQUENTIAL_EXE) + " --version");
  EXPECT_EQ(sequential.exit_code, 0);
  EXPECT_EQ(sequential.out, std::string("findmug-sequential ") + kVersion + "\n");
  struct Case {
    std::string command, expected;
  };
  const std::vector<Case> cases = {
      {replay + " --source dataset:/x --rate 0 --count 1", "--rate: must be > 0, got '0'"},
      {replay + " --source dataset:/x --rate 5 --count 1 --bogus", "--bogus"},
      {replay + " --rate 5 --count 1", "--source is required"},
      {replay + " --source dataset:/x --rate 5", "give exactly one of --duration and --count"},
      {replay + " --source dataset:/x --rate 5 --count 1 --color-compression gif", "'gif'"},
      // --url (the old name of --lcm-url) is accepted: the run gets as far as the source.
      {replay + " --source dataset:/nonexistent/replay --rate 5 --count 1 --url memq://",
       "/nonexistent/replay"},
      {probe + " --url memq:// --log x.lcm --bins 1", "--bins"},
      {probe + " --url memq:// --log x.lcm --timeout -3", "--timeout: must be > 0, got '-3'"},
      {probe + " --url memq://", "give exactly one of --log FILE and --live"},
      {probe + " --log x.lcm --expect-file n.txt", "--expect-file goes with --live"},
      {std::string(FINDMUG_SEQUENTIAL_EXE) + " --bogus", "--bogus"},
  };
  for (const auto& c : cases) {
    const ProgramRun r = runProgram(c.command);
    EXPECT_EQ(r.exit_code, 2) << c.command << "\n" << r.err;
    EXPECT_TRUE(has(r.err, c.expected))
        << c.command << "\nexpected: " << c.expected << "\ngot: " << r.err;
  }
}
#endif

}  // namespace
}  // namespace findmug
