#include "vio/cli/progress.h"

#include <sstream>

#include <gtest/gtest.h>

namespace vio::tools {
namespace {

TEST(ProgressBar, DrawsPercentAndCountWhenEnabled) {
  std::ostringstream out;
  {
    ProgressBar bar(200, "frames", &out, /*enabled=*/true);
    bar.Update(100);
    bar.Finish();
  }
  EXPECT_NE(out.str().find("100% 200/200 frames"), std::string::npos) << out.str();
  EXPECT_EQ(out.str().back(), '\n');
}

TEST(ProgressBar, PrintsNothingWhenNotATerminal) {
  std::ostringstream out;
  {
    ProgressBar bar(10, "frames", &out, /*enabled=*/false);
    for (int i = 0; i <= 10; ++i) bar.Update(i);
    bar.Finish();
  }
  EXPECT_TRUE(out.str().empty());
}

}  // namespace
}  // namespace vio::tools
