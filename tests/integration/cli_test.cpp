// The shared command-line layer (tools/cli/findmug_cli.hpp) and findmugd's flags on it:
// --help/--version/bad flags give the same exit codes everywhere, number checks name the
// flag and value, and findmugd keeps --set and its shortcuts in command-line order.
#include <gtest/gtest.h>

#include <sstream>
#include <vector>

#include "findmug/daemon/daemon_config.hpp"
#include "findmug/error.hpp"
#include "findmug/version.hpp"
#include "findmug_cli.hpp"

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

}  // namespace
}  // namespace findmug
