#include "test_data.h"

#include <cstdlib>
#include <filesystem>
#include <random>
#include <system_error>

namespace vio::test {
namespace {

// The one folder under the system's temporary directory that holds every folder this test
// process makes; created on first use, removed by RemoveTempRoot().
std::filesystem::path& TempRoot() {
  static std::filesystem::path root;
  return root;
}

std::string RandomSuffix() {
  std::random_device rd;
  return std::to_string(rd()) + std::to_string(rd());
}

}  // namespace

std::string SourceDir() {
  const char* src = std::getenv("VIO_SOURCE_DIR");
  return (src != nullptr && *src) ? src : VIO_DEFAULT_SOURCE_DIR;
}

std::string DataDir() {
  if (const char* env = std::getenv("VIO_DATA_DIR"); env != nullptr && *env) return env;
  return SourceDir() + "/../shared/data";
}

std::string EurocSequence(const std::string& name) { return DataDir() + "/euroc/" + name; }

bool PathExists(const std::string& path) { return std::filesystem::exists(path); }

std::string MakeTempDir(const std::string& prefix) {
  std::filesystem::path& root = TempRoot();
  if (root.empty()) {
    root = std::filesystem::temp_directory_path() / ("vio_test_" + RandomSuffix());
  }
  const auto dir = root / (prefix + "_" + RandomSuffix());
  std::filesystem::create_directories(dir);
  return dir.string();
}

std::string RemoveTempRoot(bool keep) {
  std::filesystem::path& root = TempRoot();
  const std::string where = root.string();
  if (!root.empty() && !keep) {
    std::error_code ignored;
    std::filesystem::remove_all(root, ignored);
  }
  root.clear();
  return keep ? where : std::string();
}

}  // namespace vio::test
