// Where the tests' inputs are: the only test source compiled with the paths of this
// checkout and build tree (test_data.hpp says why).
#include "test_data.hpp"

namespace findmug::test {

std::filesystem::path dataRoot() {
  if (const char* env = std::getenv("FINDMUG_DATA"); env && *env) return env;
  return FINDMUG_DEFAULT_DATA_DIR;
}

std::filesystem::path sourceDir() { return FINDMUG_SOURCE_DIR; }
std::filesystem::path binaryDir() { return FINDMUG_BINARY_DIR; }
std::string builtProgram(const std::string& path_in_build_tree) {
  return (binaryDir() / path_in_build_tree).string();
}

}  // namespace findmug::test
