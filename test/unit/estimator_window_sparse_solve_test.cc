// Window::SolveSparse (batch's solves: landmarks eliminated first, the reduced
// state system by sparse Cholesky, on a copy laid out by id) reaches the same
// solution as the solves it replaced (Ceres over the window's own problem with
// the whole system's sparse Cholesky), to 1e-8; it holds the constant blocks;
// two windows of one cost built in other orders solve to the same bits; and a
// refinement of every frame from other start values reaches the minimum of the
// same problem built directly.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_window.h"
#include "vio/estimator/frozen_observations.h"
#include "vio/estimator/refinement.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

constexpr int kFrames = 12;
constexpr int kFirst = 40;
constexpr double kOffsetM = 0.02;

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(5.0, 11);
  return flight;
}

SolverOptions Tight(const std::string& step, const std::string& linear_solver) {
  SolverOptions solver;
  solver.step = step;
  solver.linear_solver = linear_solver;
  solver.max_iterations = 100;
  solver.function_tolerance = 1e-16;
  solver.parameter_tolerance = 1e-14;
  return solver;
}

std::vector<double> AllValues(const Window& window) {
  std::vector<double> values;
  for (const auto& [id, s] : window.states()) {
    values.insert(values.end(), s.pose, s.pose + 7);
    values.insert(values.end(), s.speed_bias, s.speed_bias + 9);
  }
  for (const auto& [id, landmark] : window.landmarks()) values.insert(values.end(), landmark.p_w, landmark.p_w + 3);
  return values;
}

double MaxDifference(const std::vector<double>& a, const std::vector<double>& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  return worst;
}

std::vector<double> Solved(const SolverOptions& solver, bool sparse, int frames = kFrames) {
  const ModelOptions model;
  Window window(model, Flight().stereo());
  Flight().Build(window, model, kFirst, frames, kOffsetM);
  const SolveReport report = sparse ? window.SolveSparse(solver) : window.Solve(solver);
  EXPECT_TRUE(report.usable);
  EXPECT_GT(report.iterations, 1);
  return AllValues(window);
}

TEST(WindowSparseSolve, SameSolutionAsTheWholeSystemsSparseCholesky) {
  const std::vector<double> start = [] {
    const ModelOptions model;
    Window window(model, Flight().stereo());
    Flight().Build(window, model, kFirst, kFrames, kOffsetM);
    return AllValues(window);
  }();
  const std::vector<double> sparse = Solved(Tight("lm", "sparse"), true);
  const std::vector<double> old = Solved(Tight("lm", "sparse_full"), false);
  EXPECT_GT(MaxDifference(sparse, start), 1e-3);  // the solve moved the states
  EXPECT_LT(MaxDifference(sparse, old), 1e-8);
  EXPECT_LT(MaxDifference(Solved(Tight("lm", "dense"), true), old), 1e-8);  // DENSE_SCHUR on the copy
  // The whole system's sparse Cholesky on the copy, segments' interiors first
  // (45 states: two segments of 20 and the rest).
  EXPECT_LT(MaxDifference(Solved(Tight("lm", "sparse_full"), true, 45), Solved(Tight("lm", "sparse_full"), false, 45)),
            1e-8);
}

TEST(WindowSparseSolve, HoldsTheConstantBlocks) {
  const ModelOptions model;
  Window window(model, Flight().stereo());
  Flight().Build(window, model, kFirst, kFrames, kOffsetM);
  const StateId held(3);
  window.SetStateConstant(held, true);
  const LandmarkId held_landmark = window.landmarks().begin()->first;
  window.SetLandmarkConstant(held_landmark, true);
  const State before = window.state(held);
  const Eigen::Vector3d landmark_before = window.landmark(held_landmark).position();
  const Eigen::Vector3d moved_before = window.state(StateId(5)).p_w_b();
  ASSERT_TRUE(window.SolveSparse(Tight("lm", "sparse")).usable);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(window.state(held).pose[i], before.pose[i]);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(window.state(held).speed_bias[i], before.speed_bias[i]);
  EXPECT_EQ(window.landmark(held_landmark).position(), landmark_before);
  EXPECT_GT((window.state(StateId(5)).p_w_b() - moved_before).norm(), 1e-5);
}

// Without the per-block residual sets (batch's window, the refinement's) a removal scans the
// residuals: the same observation and landmark dropped, the solve reaches the same values to the last bit.
TEST(WindowSparseSolve, WithoutTheResidualIndexRemovesAndSolvesToTheSameBits) {
  const auto solved = [](ResidualIndex index) {
    const ModelOptions model;
    Window window(model, Flight().stereo(), index);
    Flight().Build(window, model, kFirst, kFrames, kOffsetM);
    const int residuals = window.num_residual_blocks();
    const Landmark& seen = window.landmarks().begin()->second;
    EXPECT_GT(seen.observed_from.size(), 2u);
    window.DropObservation(*seen.observed_from.begin(), seen.id);
    window.DropLandmark(window.landmarks().rbegin()->first);
    EXPECT_LT(window.num_residual_blocks(), residuals - 1);
    EXPECT_TRUE(window.SolveSparse(Tight("lm", "sparse_full")).usable);
    return AllValues(window);
  };
  const std::vector<double> indexed = solved(ResidualIndex::kPerBlock);
  EXPECT_EQ(solved(ResidualIndex::kNone), indexed);
}

// `source`'s states, IMU factors, landmarks and observations added to `window` with the time offset
// and the extrinsics estimated, in id order or each kind in reverse (so their blocks and residuals lie
// in another order in memory and in Ceres' problem), and an anchored point.
void CopyWindow(const Window& source, bool reversed, Window& window) {
  const auto in_order = [reversed](auto items) {
    if (reversed) std::reverse(items.begin(), items.end());
    return items;
  };
  window.EstimateTimeOffset(0.001, 0.005);
  window.EstimateExtrinsics(0.01, 0.01);
  std::vector<StateId> states;
  for (const auto& [id, s] : source.states()) states.push_back(id);
  for (StateId id : in_order(states)) {
    State& s = window.AddState(id, source.state(id).t_ns);
    std::copy(source.state(id).pose, source.state(id).pose + 7, s.pose);
    std::copy(source.state(id).speed_bias, source.state(id).speed_bias + 9, s.speed_bias);
  }
  StatePrior prior;
  prior.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
  prior.speed_bias_sigma.setConstant(0.1);
  window.AddStatePrior(states.front(), prior);
  for (StateId to : in_order(states)) {
    StateId from;
    if (const ImuPreintegration* imu = source.ImuFactorInto(to, &from)) window.AddImuFactor(from, to, *imu);
  }
  std::vector<LandmarkId> landmarks;
  for (const auto& [id, landmark] : source.landmarks()) landmarks.push_back(id);
  for (LandmarkId id : in_order(landmarks)) window.AddLandmark(id, source.landmark(id).position());
  for (StateId id : in_order(states)) {
    for (const auto& [landmark, z] : in_order(source.ObservationsOf(id))) window.AddObservation(id, landmark, z);
  }
  window.SetAnchoredPoint(states[2], landmarks.front(), Eigen::Vector3d(0.1, 0.2, 3.0), Eigen::Matrix3d::Identity());
}

// The copy SolveSparse solves is laid out by the keys the window gives each residual's blocks, the
// marginalization's columns likewise: two windows of the same cost built in other orders reach the
// same values to the last bit, through a marginalization (a prior on states, landmarks and the
// calibration blocks) and the solves of batch (observations of a held state summarized) and the refinement.
TEST(WindowSparseSolve, SameBitsForAWindowBuiltInAnotherOrder) {
  for (const bool fej : {false, true}) {
    const auto solved = [fej](bool reversed) {
      ModelOptions model;
      model.fej = fej;
      Window source(model, Flight().stereo());
      Flight().Build(source, model, kFirst, kFrames, kOffsetM);
      Window window(model, Flight().stereo());
      CopyWindow(source, reversed, window);
      const State first = window.states().begin()->second;
      const std::vector<LandmarkId> seen_first = [&] {
        std::vector<LandmarkId> only;  // landmarks only the first state sees leave with it
        for (const auto& [id, landmark] : window.landmarks()) {
          if (landmark.observed_from == std::set<StateId>{first.id} && landmark.anchored_to.empty()) only.push_back(id);
        }
        return only;
      }();
      window.Marginalize({first.id}, seen_first);
      EXPECT_EQ(window.num_priors(), 3);  // the time offset's, the extrinsics', the marginalization's
      FrozenObservations frozen;
      const StateId held = std::next(window.states().begin())->first;
      window.SummarizeObservationsOf(held, frozen);
      window.SetStateConstant(held, true);
      EXPECT_TRUE(window.SolveSparse(Tight("lm", "sparse"), frozen).usable);
      window.SetStateConstant(held, false);
      EXPECT_TRUE(window.SolveSparse(Tight("lm", "sparse_full")).usable);
      std::vector<double> values = AllValues(window);
      values.push_back(window.time_offset_s());
      for (int i = 0; i < 6; ++i) values.push_back(window.extrinsic_correction()[i]);
      return values;
    };
    const std::vector<double> in_order = solved(false);
    EXPECT_EQ(solved(true), in_order) << (fej ? "with" : "without") << " FEJ";
  }
}

// The refinement builds the whole problem from the logged measurements: from
// other start values (some states predicted by the IMU) it reaches the minimum
// that the same problem built directly reaches, to within where Ceres' gradient
// tolerance (1e-10) stops the two.
TEST(Refinement, SolvesTheLoggedFramesToTheDirectSolve) {
  EstimatorOptions options;
  MeasurementLog log;
  StatePrior prior;
  prior.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
  prior.speed_bias_sigma << Eigen::Vector3d::Constant(0.1), Eigen::Vector3d::Constant(0.01),
      Eigen::Vector3d::Constant(0.1);
  log.first_prior = prior;
  Window direct(options.model, Flight().stereo());
  Flight().Build(direct, options.model, kFirst, kFrames, kOffsetM);
  for (int k = 0; k < kFrames; ++k) {
    const StereoFrame& frame = Flight().frames()[kFirst + k];
    LoggedState logged{StateId(k), frame.t_ns, frame.observations, std::nullopt};
    if (k > 0) logged.imu = Flight().ImuBetween(kFirst + k - 1);
    log.states.push_back(logged);
  }
  const StartValue start = [&direct](const LoggedState& logged, State* s) {
    std::copy(direct.state(logged.id).pose, direct.state(logged.id).pose + 7, s->pose);
    std::copy(direct.state(logged.id).speed_bias, direct.state(logged.id).speed_bias + 9, s->speed_bias);
    return logged.id.value % 3 != 2;  // some states predicted by the IMU instead
  };
  options.batch.batch_final_iterations = 100;
  Window whole(options.model, Flight().stereo());
  const RefinementReport report = Refine(log, start, {}, options, whole);
  EXPECT_TRUE(report.usable);
  EXPECT_EQ(report.states, kFrames);
  EXPECT_EQ(report.landmarks, static_cast<int>(direct.landmarks().size()));
  ASSERT_TRUE(SolveWhole(direct, options).usable);
  SolverOptions tight = Tight("lm", "sparse");
  ASSERT_TRUE(direct.SolveSparse(tight).usable);
  ASSERT_TRUE(whole.SolveSparse(tight).usable);
  EXPECT_LT(MaxDifference(AllValues(whole), AllValues(direct)), 1e-6);
}

// The refinement starts each landmark at its last online estimate when the log has one, else
// triangulates it from all its views. At the start states of a problem built with each landmark
// stereo-triangulated from its first view (Flight::Build), the triangulation from all views starts
// lower; from that problem's solution (states and landmarks) the first cost is at most its final one
// (the first prior is centred on the start), to 1e-8.
TEST(Refinement, StartsTheLandmarksAtTheirLoggedEstimates) {
  EstimatorOptions options;
  MeasurementLog log;
  StatePrior prior;
  prior.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
  prior.speed_bias_sigma << Eigen::Vector3d::Constant(0.1), Eigen::Vector3d::Constant(0.01),
      Eigen::Vector3d::Constant(0.1);
  log.first_prior = prior;
  Window direct(options.model, Flight().stereo());
  Flight().Build(direct, options.model, kFirst, kFrames, kOffsetM);
  for (int k = 0; k < kFrames; ++k) {
    const StereoFrame& frame = Flight().frames()[kFirst + k];
    LoggedState logged{StateId(k), frame.t_ns, frame.observations, std::nullopt};
    if (k > 0) logged.imu = Flight().ImuBetween(kFirst + k - 1);
    log.states.push_back(logged);
  }
  const auto start_at = [](const std::map<StateId, State>& states) {
    return [states](const LoggedState& logged, State* s) {
      std::copy(states.at(logged.id).pose, states.at(logged.id).pose + 7, s->pose);
      std::copy(states.at(logged.id).speed_bias, states.at(logged.id).speed_bias + 9, s->speed_bias);
      return true;
    };
  };
  const std::map<StateId, State> built(direct.states().begin(), direct.states().end());
  const SolveReport solved = SolveWhole(direct, options);
  ASSERT_TRUE(solved.usable);
  Window triangulated(options.model, Flight().stereo());
  const RefinementReport from_views = Refine(log, start_at(built), {}, options, triangulated);
  LandmarkStarts landmarks;
  for (const auto& [id, landmark] : direct.landmarks()) landmarks[id] = landmark.position();
  const std::map<StateId, State> solution(direct.states().begin(), direct.states().end());
  Window started(options.model, Flight().stereo());
  const RefinementReport from_log = Refine(log, start_at(solution), landmarks, options, started);
  ASSERT_TRUE(from_log.usable && from_views.usable);
  EXPECT_EQ(from_views.started_landmarks, 0);
  EXPECT_EQ(from_views.triangulated_landmarks, static_cast<int>(landmarks.size()));
  EXPECT_LT(from_views.initial_cost, solved.initial_cost);
  EXPECT_EQ(from_log.started_landmarks, static_cast<int>(landmarks.size()));
  EXPECT_EQ(from_log.triangulated_landmarks, 0);
  EXPECT_LE(from_log.initial_cost, solved.final_cost * (1 + 1e-8));
  EXPECT_LT(from_log.initial_cost, from_views.initial_cost);
  EXPECT_LT(from_log.iterations, from_views.iterations);
}

// A start value that puts landmarks behind a camera (one state turned about
// half a turn): its observations do not evaluate there, and would fail the
// whole solve before its first iteration; they are dropped and the rest refines.
TEST(Refinement, DropsObservationsThatDoNotEvaluateAtTheStart) {
  EstimatorOptions options;
  MeasurementLog log;
  StatePrior prior;
  prior.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
  prior.speed_bias_sigma << Eigen::Vector3d::Constant(0.1), Eigen::Vector3d::Constant(0.01),
      Eigen::Vector3d::Constant(0.1);
  log.first_prior = prior;
  Window direct(options.model, Flight().stereo());
  Flight().Build(direct, options.model, kFirst, kFrames, kOffsetM);
  for (int k = 0; k < kFrames; ++k) {
    const StereoFrame& frame = Flight().frames()[kFirst + k];
    LoggedState logged{StateId(k), frame.t_ns, frame.observations, std::nullopt};
    if (k > 0) logged.imu = Flight().ImuBetween(kFirst + k - 1);
    log.states.push_back(logged);
  }
  const Eigen::Vector3d optical_axis = Flight().stereo().T_b_cl.linear() * Eigen::Vector3d::UnitZ();
  const Eigen::Quaterniond half_turn(Eigen::AngleAxisd(M_PI, optical_axis.unitOrthogonal()));
  const StartValue start = [&direct, &half_turn](const LoggedState& logged, State* s) {
    std::copy(direct.state(logged.id).pose, direct.state(logged.id).pose + 7, s->pose);
    std::copy(direct.state(logged.id).speed_bias, direct.state(logged.id).speed_bias + 9, s->speed_bias);
    if (logged.id.value == kFrames - 1) s->SetPose(s->p_w_b(), (s->q_w_b() * half_turn).normalized());
    return true;
  };
  Window whole(options.model, Flight().stereo());
  const RefinementReport report = Refine(log, start, {}, options, whole);
  EXPECT_GT(report.dropped_observations, 0);
  EXPECT_LT(report.dropped_observations, static_cast<int>(log.states.back().observations.size()) + 1);
  EXPECT_TRUE(report.usable);
  EXPECT_GT(report.iterations, 0);
  EXPECT_EQ(report.states, kFrames);
}

}  // namespace
}  // namespace vio
