// Test support: locating the third-party data and scratch directories.
//
// Data comes from $FINDMUG_DATA, else ../shared/data beside the checkout.
// When it is missing, a test is skipped on a developer machine but FAILS
// under CI=true, so CI can never pass without having looked at real data.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include <unistd.h>

namespace findmug::test {

// $FINDMUG_DATA, else the build's default (../shared/data beside the checkout).
std::filesystem::path dataRoot();

inline bool runningInCi() {
  const char* ci = std::getenv("CI");
  return ci && std::string(ci) == "true";
}

// Path of `relative` under the data root, or empty when it does not exist.
inline std::filesystem::path dataPath(const std::string& relative) {
  auto p = dataRoot() / relative;
  return std::filesystem::exists(p) ? p : std::filesystem::path();
}

// The checkout and the build tree the tests were built from. Compiled into
// test_data.cpp alone: a path on every test file's command line would give each of
// them another ccache key in every clone, and CI compiles each fresh clone.
std::filesystem::path sourceDir();
std::filesystem::path binaryDir();
// A program of this build by its path inside the build tree (the tests' FINDMUG_*_EXE
// macros, tests/CMakeLists.txt: findmug_test_program_paths).
std::string builtProgram(const std::string& path_in_build_tree);

// A fresh directory under the system temp dir, removed at scope exit.
class TempDir {
 public:
  TempDir() {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("findmug-test-" + std::to_string(rd()) + "-" + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string str(const std::string& name = "") const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace findmug::test

// Use at the top of a test that needs root (a private network namespace):
// skips on a developer's unprivileged machine, FAILS under CI=true (CI runs as
// root, so a skip there would hide a test that never ran).
#define FINDMUG_REQUIRE_ROOT()                                                           \
  if (::geteuid() != 0) {                                                                \
    if (::findmug::test::runningInCi()) FAIL() << "needs root under CI=true";            \
    GTEST_SKIP() << "needs root for a private network namespace";                         \
  }

// Use at the top of a test that needs the data: skips locally, fails in CI.
#define FINDMUG_REQUIRE_DATA(var, relative)                                              \
  const std::filesystem::path var = ::findmug::test::dataPath(relative);                 \
  if (var.empty()) {                                                                     \
    if (::findmug::test::runningInCi()) {                                                \
      FAIL() << "test data missing under CI=true: " << (::findmug::test::dataRoot() / relative) \
             << " (set FINDMUG_DATA)";                                                   \
    }                                                                                    \
    GTEST_SKIP() << "test data missing: " << (::findmug::test::dataRoot() / relative);   \
  }
