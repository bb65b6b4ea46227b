#include <cstdlib>
#include <iostream>
#include <string>

#include <gflags/gflags.h>
#include <glog/logging.h>
#include <gtest/gtest.h>

#include "test_data.h"

// Runs the tests; the folders they made are removed afterwards unless a test failed or
// VIO_KEEP_TEST_DIRS is set, in which case their location is printed.
int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  FLAGS_minloglevel = google::GLOG_WARNING;
  const int status = RUN_ALL_TESTS();
  const char* keep_env = std::getenv("VIO_KEEP_TEST_DIRS");
  const bool keep = status != 0 || (keep_env != nullptr && *keep_env != '\0');
  const std::string kept = vio::test::RemoveTempRoot(keep);
  if (!kept.empty()) std::cerr << "test folders kept in " << kept << "\n";
  return status;
}
