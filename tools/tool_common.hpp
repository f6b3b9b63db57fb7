// Shared command-line plumbing of the findmug tools: flags, config, progress.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "findmug/config.hpp"

namespace findmug::tools {

// Minimal flag parser: --name value, --name=value, boolean --flag.
// Repeated flags keep every value (e.g. --set k=v --set k2=v2).
class Flags {
 public:
  Flags(int argc, char** argv, const std::vector<std::string>& boolean_flags);
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::string get(const std::string& name, const std::string& fallback = "") const;
  std::vector<std::string> getAll(const std::string& name) const;
  int getInt(const std::string& name, int fallback) const;
  // Throws findmug::Error naming the first flag not in `known`.
  void allowOnly(const std::vector<std::string>& known) const;

 private:
  std::map<std::string, std::vector<std::string>> values_;
};

// --config FILE (optional) then every --set key=value on top.
Config configFromFlags(const Flags& flags);

// A one-line progress bar on stderr when it is a terminal; silent otherwise.
class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  void update(int done, int total);
  void finish();

 private:
  std::string label_;
  bool tty_;
  bool drawn_ = false;
};

}  // namespace findmug::tools
