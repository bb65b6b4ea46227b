#pragma once
// Where the tests find the real EuRoC data of ../shared/data.
//
// The folder comes from $VIO_DATA_DIR, else `../shared/data` relative to the
// project root. Tests that need it call VIO_REQUIRE_DATA(path), which skips the
// test with a message that names the missing folder: a user's clone has no
// ../shared, CI has it.
#include <string>

#include <gtest/gtest.h>

namespace vio::test {

/// The project's source folder ($VIO_SOURCE_DIR, else where it was built from).
std::string SourceDir();

/// The real-data root ($VIO_DATA_DIR or <project>/../shared/data).
std::string DataDir();

/// <DataDir()>/euroc/<name>: an ASL sequence folder (the one holding mav0/).
std::string EurocSequence(const std::string& name);

/// True when `path` exists.
bool PathExists(const std::string& path);

/// A fresh, empty temporary folder for one test (removed at exit is not
/// guaranteed; it lives under the system temp dir).
// A new, empty folder `<prefix>_<random>` inside this test process's own temporary root.
std::string MakeTempDir(const std::string& prefix);

// Removes the process's temporary root and everything in it, unless `keep`; returns the root's
// path when it was kept (empty otherwise). test_main calls it after the tests.
std::string RemoveTempRoot(bool keep);

}  // namespace vio::test

#define VIO_REQUIRE_DATA(path)                                                 \
  do {                                                                         \
    if (!::vio::test::PathExists(path)) {                                      \
      GTEST_SKIP() << "real data not found at " << (path)                      \
                   << " (set VIO_DATA_DIR to the folder holding euroc/)";     \
    }                                                                          \
  } while (0)
