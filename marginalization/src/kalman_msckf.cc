// MSCKF sub-blocks of the design paper, appendix Algorithms 10-12.
#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>

#include "equivalence_internal.h"
#include "vio/marginalization/kalman_reference.h"

namespace vio::marginalization {
namespace {

using internal::RequireGaussian;
using internal::Symmetrized;

/// A linear measurement r = T δ + n, n ~ N(0, R).
struct LinearMeasurement {
  Eigen::MatrixXd T;
  Eigen::VectorXd r;
  Eigen::MatrixXd R;
};

/// Algorithm 11, lines 7-8: an orthonormal basis A of the left null space of
/// H_f (A^T H_f = 0), the trailing columns of the Q of a rank-revealing QR.
Eigen::MatrixXd LeftNullSpaceBasis(const Eigen::MatrixXd& H_f) {
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(H_f);
  VIO_REQUIRE_INPUT(qr.rank() == H_f.cols());  // every feature is observable
  const Eigen::MatrixXd Q = qr.householderQ();
  return Q.rightCols(H_f.rows() - qr.rank());
}

/// Algorithm 11, line 9: Q T = QR of the projected Jacobian; the rotated
/// system is (T, Q^T r, Q^T R Q). Rows of T below its column count are zero:
/// they are conditioned away (see kalman_reference.h).
LinearMeasurement CompressByQr(const LinearMeasurement& projected) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(projected.T);
  const Eigen::MatrixXd Q = qr.householderQ();
  LinearMeasurement rotated;
  rotated.T = qr.matrixQR().triangularView<Eigen::Upper>();
  rotated.r = Q.transpose() * projected.r;
  rotated.R = Symmetrized(Q.transpose() * projected.R * Q);
  const Eigen::Index rows = rotated.T.rows();
  const Eigen::Index kept = std::min(rows, rotated.T.cols());
  if (kept == rows) return rotated;

  const Eigen::Index dropped = rows - kept;
  const Eigen::LLT<Eigen::MatrixXd> R22(rotated.R.bottomRightCorner(dropped, dropped));
  VIO_REQUIRE_INPUT(R22.info() == Eigen::Success);  // Σ̃_v positive definite
  const Eigen::MatrixXd R12 = rotated.R.topRightCorner(kept, dropped);
  LinearMeasurement compressed;
  compressed.T = rotated.T.topRows(kept);
  compressed.r = rotated.r.head(kept) - R12 * R22.solve(rotated.r.tail(dropped));
  compressed.R = Symmetrized(rotated.R.topLeftCorner(kept, kept) - R12 * R22.solve(R12.transpose()));
  return compressed;
}

}  // namespace

// Algorithm 10, lines 4-5.
Gaussian MsckfAugmentPose(const Gaussian& state, const Eigen::VectorXd& new_pose_mean,
                          const Eigen::MatrixXd& Psi) {
  RequireGaussian(state);
  const Eigen::Index d = state.covariance.rows();
  VIO_REQUIRE_SHAPE(Psi, Psi.rows(), d);
  Eigen::MatrixXd I_Psi(d + Psi.rows(), d);  // [I; Ψ]
  I_Psi << Eigen::MatrixXd::Identity(d, d), Psi;
  Gaussian augmented;
  augmented.mean.resize(state.mean.size() + new_pose_mean.size());
  augmented.mean << state.mean, new_pose_mean;
  augmented.covariance = Symmetrized(I_Psi * state.covariance * I_Psi.transpose());
  return augmented;
}

// Algorithm 11: null-space projection (lines 7-8), QR (line 9), EKF update
// (lines 10-11, Algorithm 7 on the projected, compressed system).
Gaussian MsckfFeatureUpdate(const Gaussian& state, const StateLayout& layout,
                            const LinearizedMeasurements& measurements) {
  const Eigen::Index m = measurements.innovation.size();
  VIO_REQUIRE_SHAPE(measurements.H_x, m, layout.TangentSize());
  VIO_REQUIRE_SHAPE(measurements.H_f, m, measurements.H_f.cols());
  VIO_REQUIRE_SHAPE(measurements.Sigma_v, m, m);
  const Eigen::MatrixXd A = LeftNullSpaceBasis(measurements.H_f);
  if (A.cols() == 0) return state;  // the features absorb every measurement

  const LinearMeasurement projected{A.transpose() * measurements.H_x, A.transpose() * measurements.innovation,
                                    A.transpose() * measurements.Sigma_v * A};
  const LinearMeasurement compressed = CompressByQr(projected);
  return EkfUpdate(state, layout,
                   LinearizedMeasurements{compressed.r, compressed.T, Eigen::MatrixXd(), compressed.R});
}

// Algorithm 12, lines 2-4 (with O for the poses' process noise).
Gaussian MsckfPropagate(const Gaussian& state, const LinearizedDynamics& dynamics) {
  RequireGaussian(state);
  const Eigen::Index d = state.covariance.rows();
  const Eigen::Index d_imu = dynamics.G.rows();
  VIO_REQUIRE_INPUT(d_imu <= d && dynamics.g_of_mean.size() <= state.mean.size());
  VIO_REQUIRE_SHAPE(dynamics.G, d_imu, d_imu);
  VIO_REQUIRE_SHAPE(dynamics.Sigma_w, d_imu, d_imu);

  Eigen::MatrixXd Phi = Eigen::MatrixXd::Identity(d, d);  // diag(G_t, I)
  Phi.topLeftCorner(d_imu, d_imu) = dynamics.G;
  Eigen::MatrixXd noise = Eigen::MatrixXd::Zero(d, d);  // diag(Σ_w, O)
  noise.topLeftCorner(d_imu, d_imu) = dynamics.Sigma_w;
  Gaussian propagated;
  propagated.mean = state.mean;
  propagated.mean.head(dynamics.g_of_mean.size()) = dynamics.g_of_mean;
  propagated.covariance = Symmetrized(Phi * state.covariance * Phi.transpose() + noise);
  return propagated;
}

}  // namespace vio::marginalization
