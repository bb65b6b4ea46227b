#pragma once
// The camera-IMU rotation search at initialization (docs/calibration.md): the rig's rotation
// recovered from the gyro's rotations against the stereo camera's over frame pairs (hand-eye
// rotation), for a sensor.yaml whose T_BS is off by more than the online correction's prior covers.
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace vio {

/// Fits the rotation Q and a constant gyro bias b in
///   theta_gyro_i - b dt_i = Q theta_camera_i
/// over frame pairs i, theta_camera the camera's rotation vector in the body frame under the given
/// rig (R_b_c), theta_gyro the gyro's rotation over the pair. With the true rig R_b_c' = Q R_b_c the
/// two agree. A 3D-3D fit of stereo points shrinks the camera's rotation about some axes more than
/// about others (depth noise): a linear map A = Q P (P symmetric positive) and b are fitted by
/// linear least squares, Q is A's polar factor.
class RigRotationSearch {
 public:
  struct Options {
    int decision_pairs = 100;             ///< decides with at least this many pairs
    double decision_rotation_rad = 10.0;  ///< ... and this much camera rotation summed over them [rad]
    double decision_sigma_rad = 0.003;    ///< ... once the fit's sigma is below this [rad] (0.17 deg)
    double min_pair_rotation_rad = 0.1;   ///< pairs with less camera rotation are left out (only noise)
  };
  struct Result {
    Eigen::Matrix3d Q = Eigen::Matrix3d::Identity();         ///< the rig's turn in the body
    Eigen::Vector3d rotation_vector = Eigen::Vector3d::Zero();  ///< Log(Q) [rad]
    Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();     ///< [rad/s]
    /// The largest standard deviation of Log(Q) over directions, from the residuals and the pairs'
    /// excitation (optimistic: the pairs overlap) [rad]; infinite when an axis is not excited.
    double sigma_rad = 0;
    int pairs = 0;
    double rotation_rad = 0;  ///< camera rotation summed over the pairs
  };

  RigRotationSearch() : RigRotationSearch(Options()) {}
  explicit RigRotationSearch(const Options& options) : options_(options) {}

  /// One frame pair: the gyro's integrated readings and the camera's rotation vector [rad], body
  /// frame, and its length dt_s [s].
  void AddPair(const Eigen::Vector3d& theta_gyro, const Eigen::Vector3d& theta_camera, double dt_s);
  /// The result once enough pairs were seen (Options' decision thresholds), else nothing.
  const std::optional<Result>& result() const { return result_; }
  /// Decides with the pairs so far (the caller's time is up): the result when at least
  /// decision_pairs were seen (its sigma tells whether they told the rotation), else nothing.
  const std::optional<Result>& Decide();
  /// The fit over the pairs so far (sigma infinite with fewer than 3), whether or not decided.
  Result Fit() const;

 private:
  struct Pair {
    Eigen::Vector3d theta_gyro, theta_camera;
    double dt_s;
  };
  Options options_;
  std::vector<Pair> pairs_;
  double rotation_rad_ = 0;
  std::optional<Result> result_;
};

}  // namespace vio
