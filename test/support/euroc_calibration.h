#pragma once
// The EuRoC stereo calibration (mav0/cam0 and cam1 sensor.yaml, the same for
// every sequence), for tests that must not depend on the dataset reader.
#include <vector>

#include "vio/estimator/types.h"

namespace vio::test {

/// T from its first three rows, row-major (EuRoC's T_BS data).
inline Eigen::Isometry3d FromRowMajor(const std::vector<double>& m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = m[4 * r + c];
  }
  return T;
}

/// cam0 (left) or cam1 (right).
inline CameraCalibration EurocCamera(int camera) {
  CameraCalibration cam;
  if (camera == 0) {
    cam.intrinsics = Eigen::Vector4d(458.654, 457.296, 367.215, 248.375);
    cam.distortion = Eigen::Vector4d(-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05);
    cam.T_b_c = FromRowMajor({0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
                              0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
                              -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949});
  } else {
    cam.intrinsics = Eigen::Vector4d(457.587, 456.134, 379.999, 255.238);
    cam.distortion = Eigen::Vector4d(-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05);
    cam.T_b_c = FromRowMajor({0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,
                              0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,
                              -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038});
  }
  return cam;
}

}  // namespace vio::test
