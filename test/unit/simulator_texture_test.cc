// Image textures: a missing folder falls back to procedural textures with a
// warning; texture options out of range are errors.
#include <mutex>
#include <string>
#include <vector>

#include <glog/logging.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/simulator/texture.h"

namespace vio::tools {
namespace {

// Collects the WARNING messages logged while it lives.
class WarningCollector : public google::LogSink {
 public:
  WarningCollector() { google::AddLogSink(this); }
  ~WarningCollector() override { google::RemoveLogSink(this); }
  void send(google::LogSeverity severity, const char*, const char*, int, const struct ::tm*, const char* message,
            size_t length) override {
    if (severity != google::GLOG_WARNING) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    text_ += std::string(message, length) + "\n";
  }
  std::string text() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return text_;
  }

 private:
  std::mutex mutex_;
  std::string text_;
};

TEST(SimulatorTextureTest, MissingFolderFallsBackToProceduralWithAWarning) {
  const std::string missing = test::MakeTempDir("vio_texture") + "/no_such_folder";
  ImageTextureOptions options;
  options.dirs = missing;
  WarningCollector warnings;
  const ImageTextures textures = LoadImageTextures(options);
  EXPECT_TRUE(textures.empty());
  EXPECT_NE(warnings.text().find(missing + ": no such folder"), std::string::npos) << warnings.text();
  EXPECT_NE(warnings.text().find("procedural textures"), std::string::npos) << warnings.text();
}

TEST(SimulatorTextureTest, FolderWithoutImagesWarnsAndNoFolderIsSilent) {
  const std::string empty = test::MakeTempDir("vio_texture_empty");
  ImageTextureOptions options;
  options.dirs = empty;
  {
    WarningCollector warnings;
    EXPECT_TRUE(LoadImageTextures(options).empty());
    EXPECT_NE(warnings.text().find("no readable .png/.jpg image"), std::string::npos) << warnings.text();
  }
  options.dirs = "";
  WarningCollector warnings;
  EXPECT_TRUE(LoadImageTextures(options).empty());
  EXPECT_EQ(warnings.text(), "");  // procedural on purpose
}

TEST(SimulatorTextureTest, OptionsOutOfRangeAreErrors) {
  ImageTextureOptions options;
  options.texel_m = 0.0;
  EXPECT_THROW(CheckImageTextureOptions(options), std::invalid_argument);
  options = ImageTextureOptions();
  options.crop = 1.5;
  EXPECT_THROW(CheckImageTextureOptions(options), std::invalid_argument);
  options = ImageTextureOptions();
  options.max_images_per_dir = 0;
  EXPECT_THROW(LoadImageTextures(options), std::invalid_argument);
}

}  // namespace
}  // namespace vio::tools
