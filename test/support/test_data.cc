#include "test_data.h"

#include <cstdlib>
#include <filesystem>
#include <random>

namespace vio::test {

std::string DataDir() {
  if (const char* env = std::getenv("VIO_DATA_DIR"); env != nullptr && *env) return env;
  const char* src = std::getenv("VIO_SOURCE_DIR");
  const std::string root = (src != nullptr && *src) ? src : VIO_DEFAULT_SOURCE_DIR;
  return root + "/../shared/data";
}

std::string EurocSequence(const std::string& name) { return DataDir() + "/euroc/" + name; }

bool PathExists(const std::string& path) { return std::filesystem::exists(path); }

std::string MakeTempDir(const std::string& prefix) {
  std::random_device rd;
  const auto dir = std::filesystem::temp_directory_path() /
                   (prefix + "_" + std::to_string(rd()) + std::to_string(rd()));
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace vio::test
