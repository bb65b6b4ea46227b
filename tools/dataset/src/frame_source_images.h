#pragma once
// The image front ends (brisk, klt) as a FrameSource: stereo pairs read
// lazily, one per frame, from <root>/mav0/cam{0,1}/data/ or from the ROS 1
// bag or ROS 2 recording the dataset was read from.
#include <memory>

#include "vio/dataset/frame_source.h"

namespace vio::tools {

/// Pairs cam0 and cam1 rows with equal stamps (cam0 rows without a cam1 twin
/// are skipped). Throws std::runtime_error when the dataset has no images.
std::unique_ptr<FrameSource> MakeImageFrameSource(const FrontendOptions& options, const EurocDataset& dataset,
                                                  const frontend::StereoRectifier& rectifier);

}  // namespace vio::tools
