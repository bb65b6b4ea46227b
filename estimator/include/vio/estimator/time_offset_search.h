#pragma once
// The coarse camera-IMU time offset search at initialization (docs/calibration.md): the gyro's
// rotation against the stereo camera's, over frame pairs, for every offset on a grid. The online
// estimate (StereoCalibrationFactor) is a linearization that converges from within a few of its
// prior sigmas; the search brings offsets up to its range there.
#include <deque>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "vio/estimator/types.h"

namespace vio {

/// Fits delta [s] in
///   theta_camera(t0, t1) = G(t1 - delta) - G(t0 - delta) - b (t1 - t0)
/// over frame pairs, G the gyro's readings integrated over time (as a vector), b an unknown constant
/// gyro bias fitted for each delta in closed form; every delta on a grid of `step_s` over
/// [-max_offset_s, max_offset_s] is tried and the best refined by a parabola through its neighbours.
/// The pairs' times are IMU times under the offset applied while they were taken (`t_cam - applied`);
/// the offset is then `applied + delta` (an image stamped t was taken at IMU time t - offset).
/// A pair is scored once the gyro covers [t0 - max_offset_s, t1 + max_offset_s]; the gyro's history
/// is kept only that far back.
class TimeOffsetSearch {
 public:
  struct Options {
    double max_offset_s = 0.1;    ///< the range searched, either side [s]; > 0
    double step_s = 0.001;        ///< the grid [s]; > 0
    int decision_pairs = 100;     ///< decides with at least this many scored pairs
    double decision_rotation_rad = 10.0;  ///< ... and this much camera rotation summed over them [rad]
  };
  struct Result {
    double delta_s = 0;        ///< the best offset change [s]
    double sigma_s = 0;        ///< its standard deviation from the cost's curvature [s] (the pairs overlap: optimistic)
    bool at_bound = false;     ///< the best grid point is an end of the range: the offset may lie beyond it
    /// How much better delta_s fits than 0: the cost's decrease over the residuals' variance (a
    /// chi-square with one degree of freedom when 0 is right: above 25, 5 sigmas).
    double improvement = 0;
    int pairs = 0;
    double rotation_rad = 0;
  };

  explicit TimeOffsetSearch(const Options& options);

  /// A gyro reading [rad/s], in time order.
  void AddGyro(Timestamp t_ns, const Eigen::Vector3d& gyro_rad_s);
  /// One frame pair: its IMU times under the applied offset and the camera's rotation vector
  /// between them, in the body frame [rad].
  void AddPair(Timestamp t0_ns, Timestamp t1_ns, const Eigen::Vector3d& theta_camera);
  /// The result once enough pairs were scored (Options' decision thresholds), else nothing.
  const std::optional<Result>& result() const { return result_; }

 private:
  struct GyroSample {
    Timestamp t_ns;
    Eigen::Vector3d rate;      ///< [rad/s]
    Eigen::Vector3d integral;  ///< the readings integrated from the first kept sample up to this one [rad]
  };
  struct Pair {
    Timestamp t0_ns, t1_ns;
    Eigen::Vector3d theta_camera;
  };

  /// G(t) - G(first kept sample), the rate linearly interpolated; `t_ns` within the history.
  Eigen::Vector3d Integral(Timestamp t_ns) const;
  bool Covers(const Pair& pair) const;
  void Score(const Pair& pair);
  void ScoreReadyPairs();
  void Decide();
  /// The bias-free cost at grid point k: sum |r|^2 - |sum r dt|^2 / sum dt^2.
  double Cost(std::size_t k) const;
  Timestamp Delta(std::size_t k) const;

  Options options_;
  Timestamp max_offset_ns_;
  Timestamp step_ns_;
  std::deque<GyroSample> gyro_;
  std::deque<Pair> pending_;
  // Per grid point: sum |r|^2 and sum r dt; and sum dt^2 (the same for every point).
  std::vector<double> sum_rr_;
  std::vector<Eigen::Vector3d> sum_r_dt_;
  double sum_dt_dt_ = 0;
  int pairs_ = 0;
  double rotation_rad_ = 0;
  std::optional<Result> result_;
};

}  // namespace vio
