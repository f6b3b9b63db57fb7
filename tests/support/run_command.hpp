// Test support: running a program as a user would, and reading what it wrote.
//
// runCommand runs a shell command line with its standard error joined to its
// standard output and returns both with the exit code (-1 when it did not exit
// normally); readFile returns a file's text ("" when it cannot be read).
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace findmug::test {

struct RunResult {
  int exit_code = -1;
  std::string output;
};

inline RunResult runCommand(const std::string& command) {
  RunResult r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline std::string readFile(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace findmug::test
