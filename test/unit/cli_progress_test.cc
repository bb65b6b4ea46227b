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

// A long solve's note follows the count, and a shorter line blanks what the longer one left.
TEST(ProgressBar, DrawsANoteAndClearsIt) {
  std::ostringstream out;
  {
    ProgressBar bar(10, "frames", &out, /*enabled=*/true);
    bar.SetNote("final solve: iteration 3/20, cost 1.5e+02");
    EXPECT_NE(out.str().find("0/10 frames 0.0s  final solve: iteration 3/20, cost 1.5e+02"), std::string::npos)
        << out.str();
    const size_t with_note = out.str().size() - out.str().rfind('\r');
    bar.SetNote("");
    const size_t without_note = out.str().size() - out.str().rfind('\r');
    EXPECT_EQ(without_note, with_note) << "padded over the note";
    EXPECT_EQ(out.str().find("  final", out.str().rfind('\r')), std::string::npos);
  }
}

// A log line goes where the bar was: the bar's line is blanked first.
TEST(ProgressBar, ClearsItsLineForALogLine) {
  std::ostringstream out;
  ProgressBar bar(10, "frames", &out, /*enabled=*/true);
  bar.SetNote("solve");
  const size_t drawn = out.str().size() - 1;  // after its '\r'
  bar.ClearLine();
  EXPECT_EQ(out.str().substr(out.str().size() - drawn - 2), "\r" + std::string(drawn, ' ') + "\r");
}

}  // namespace
}  // namespace vio::tools
