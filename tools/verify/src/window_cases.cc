// The cases of `vio verify` (see window_cases.h): random scenes around a true
// one (SE3 poses with speed and biases, landmarks 3-8 m in front of the
// camera), noisy stereo measurements and IMU intervals, and a filter state
// N(μ, Σ) with μ = truth ⊞ a draw of Σ.
#include "window_cases.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>
#include <utility>

#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/stereo_geometry.h"
#include "vio/estimator/imu_factor.h"
#include "vio/marginalization/marginalization_prior.h"

namespace vio::tools::window_cases {
namespace {

constexpr int kStateAmbient = kPoseSize + kSpeedBiasSize;  // 16
constexpr int kStateTangent = 15;
constexpr double kImuDt = 0.005;    // [s] IMU sample interval
constexpr int kImuSteps = 20;       // 0.1 s between states
constexpr double kImuNoiseScale = 20.0;  // on the EuRoC densities: keeps the IMU information within 1e6 of the prior's
constexpr double kLinearScale = 30.0;    // Jacobian entries of the linear factors, like pixels per metre

const PoseManifold& Manifold() {
  static const PoseManifold manifold;
  return manifold;
}

class Random {
 public:
  explicit Random(unsigned seed) : engine_(seed) {}
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  int Integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }
  Eigen::VectorXd Normal(Eigen::Index n) {
    return Eigen::VectorXd::NullaryExpr(n, [this] { return normal_(engine_); });
  }
  Eigen::MatrixXd Normal(Eigen::Index rows, Eigen::Index cols) {
    return Eigen::MatrixXd::NullaryExpr(rows, cols, [this] { return normal_(engine_); });
  }
  Eigen::Vector3d Uniform3(double lo, double hi) { return {Uniform(lo, hi), Uniform(lo, hi), Uniform(lo, hi)}; }
  std::vector<int> Subset(int n, int count) {
    std::vector<int> all(static_cast<size_t>(n));
    std::iota(all.begin(), all.end(), 0);
    std::shuffle(all.begin(), all.end(), engine_);
    all.resize(static_cast<size_t>(count));
    return all;
  }
  /// D C D: standard deviations `sigma`, correlations of a random covariance
  /// with eigenvalues in [0.2, 1].
  Eigen::MatrixXd Covariance(const Eigen::VectorXd& sigma) {
    const Eigen::Index n = sigma.size();
    const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(Normal(n, n)).householderQ();
    Eigen::VectorXd lambda(n);
    for (Eigen::Index i = 0; i < n; ++i) lambda(i) = Uniform(0.2, 1.0);
    const Eigen::MatrixXd S = Q * lambda.asDiagonal() * Q.transpose();
    const Eigen::VectorXd scale = sigma.cwiseQuotient(S.diagonal().cwiseSqrt());
    const Eigen::MatrixXd Sigma = scale.asDiagonal() * S * scale.asDiagonal();
    return 0.5 * (Sigma + Sigma.transpose());
  }

 private:
  std::mt19937 engine_;
  std::normal_distribution<double> normal_;
};

std::runtime_error Error(const std::string& what) { return std::runtime_error(std::string(__FILE__) + ": " + what); }

// ---------------------------------------------------------------------------
// The models.

Eigen::Vector3d Project(const State& s, const Eigen::Vector3d& p_w_l) {
  Eigen::Vector3d z;
  if (!StereoFactor::Project(Stereo(), s.p_w_b(), s.q_w_b().normalized(), p_w_l, &z)) {
    throw Error("a landmark is behind the camera");
  }
  return z;
}

Eigen::Vector3d Triangulate(const State& s, const Eigen::Vector3d& z) {
  const std::optional<Eigen::Vector3d> p_c = TriangulateRectified(z, Stereo(), 1.0);
  if (!p_c) throw Error("disparity too small to triangulate");
  return s.p_w_b() + s.q_w_b().normalized() * (Stereo().T_b_cl * *p_c);
}

ImuCalibration Imu() {
  ImuCalibration imu;
  imu.gyro_noise_density *= kImuNoiseScale;
  imu.accel_noise_density *= kImuNoiseScale;
  imu.gyro_random_walk *= kImuNoiseScale;
  imu.accel_random_walk *= kImuNoiseScale;
  return imu;
}

/// 0.1 s of constant readings from the true state: a random body rate and
/// world acceleration, linearized at the filter's bias.
std::shared_ptr<const ImuPreintegration> ImuInterval(const State& truth, const State& filter, Random* random) {
  auto preintegration = std::make_shared<ImuPreintegration>(ImuBias{filter.gyro_bias(), filter.accel_bias()}, Imu());
  const Eigen::Vector3d gyro = random->Uniform3(-0.3, 0.3) + truth.gyro_bias();
  const Eigen::Vector3d a_w = random->Uniform3(-0.5, 0.5);
  const Eigen::Vector3d accel = truth.q_w_b().normalized().conjugate() * (a_w - Gravity()) + truth.accel_bias();
  for (int k = 0; k < kImuSteps; ++k) preintegration->Integrate(kImuDt, gyro, accel);
  return preintegration;
}

/// The state where the IMU factor from `from` has zero residual (Newton).
State Predict(const State& from, StateId to_id, const std::shared_ptr<const ImuPreintegration>& imu) {
  Values values;
  values.states[from.id] = from;
  State& to = values.states[to_id] = from;
  to.id = to_id;
  const Factor factor{Factor::Kind::kImu, {{from.id, to_id}, {}}, {}, imu, {}, {}};
  const Variables target{{to_id}, {}};
  for (int iteration = 0; iteration < 20; ++iteration) {
    const Linearization lin = Linearize({factor}, values, target);
    if (lin.e0.norm() < 1e-13) break;
    const Eigen::VectorXd step = -lin.J.partialPivLu().solve(lin.e0);
    values.Unstack(target, target.Layout().Plus(values.Stack(target), step));
  }
  return values.states.at(to_id);
}

// ---------------------------------------------------------------------------
// Scenes.

Eigen::VectorXd StateSigma() {
  Eigen::VectorXd sigma(kStateTangent);
  sigma << Eigen::Vector3d::Constant(0.05), Eigen::Vector3d::Constant(0.02), Eigen::Vector3d::Constant(0.1),
      Eigen::Vector3d::Constant(0.005), Eigen::Vector3d::Constant(0.05);
  return sigma;
}

/// Near the origin, any heading, slightly tilted, moving forward, small biases.
State TrueState(StateId id, Random* random) {
  State s;
  s.id = id;
  const Eigen::Quaterniond q = so3::ExpQuaternion({0.0, 0.0, random->Uniform(-3.1, 3.1)}) *
                               so3::ExpQuaternion({random->Uniform(-0.1, 0.1), random->Uniform(-0.1, 0.1), 0.0});
  s.SetPose(Eigen::Vector3d(random->Uniform(-1, 1), random->Uniform(-1, 1), random->Uniform(0.5, 1.5)), q);
  s.SetSpeedBias(q * Eigen::Vector3d(random->Uniform(0.5, 1.5), random->Uniform(-0.3, 0.3), random->Uniform(-0.2, 0.2)),
                 random->Uniform3(-0.01, 0.01), random->Uniform3(-0.05, 0.05));
  return s;
}

/// A state `forward` metres ahead of `s` (body x), slightly shifted and turned.
State NearbyState(const State& s, StateId id, double forward, Random* random) {
  State n = s;
  n.id = id;
  const Eigen::Vector3d offset(forward, random->Uniform(-0.1, 0.1), random->Uniform(-0.05, 0.05));
  n.SetPose(s.p_w_b() + s.q_w_b() * offset, s.q_w_b() * so3::ExpQuaternion(random->Uniform3(-0.05, 0.05)));
  return n;
}

/// 3-8 m ahead of the body (the camera looks along body x).
Eigen::Vector3d LandmarkInFront(const State& s, Random* random) {
  const Eigen::Vector3d p_b(random->Uniform(3, 8), random->Uniform(-2, 2), random->Uniform(-1.5, 1.5));
  return s.p_w_b() + s.q_w_b() * p_b;
}

/// The truth of a case and how its factors are drawn.
class Scene {
 public:
  Scene(bool linear, Random* random) : linear_(linear), random_(random) {}

  Values truth;

  /// N(truth ⊞ δ, Σ), δ ~ N(0, Σ), over `variables`; sets the point there.
  marginalization::Gaussian Prior(const Variables& variables, Values* point) {
    Eigen::VectorXd sigma(variables.TangentSize());
    for (size_t i = 0; i < variables.states.size(); ++i) sigma.segment(15 * i, 15) = StateSigma();
    sigma.tail(3 * variables.landmarks.size()).setConstant(0.1);
    const Eigen::MatrixXd Sigma = random_->Covariance(sigma);
    const Eigen::LLT<Eigen::MatrixXd> llt(Sigma);
    const marginalization::StateLayout layout = variables.Layout();
    const Eigen::VectorXd mean = layout.Plus(truth.Stack(variables), llt.matrixL() * random_->Normal(sigma.size()));
    point->Unstack(variables, mean);
    return {mean, Sigma};
  }

  /// Stereo of landmark l from state s (measured from the truth), or its
  /// linear stand-in.
  Factor Observation(StateId s, LandmarkId l) {
    if (linear_) return LinearFactor({{s}, {l}}, 3, /*zero_residual=*/false);
    const Eigen::Vector3d z = Project(truth.states.at(s), truth.landmarks.at(l)) + random_->Normal(3);
    return {Factor::Kind::kStereo, {{s}, {l}}, z, nullptr, {}, {}};
  }

  /// IMU interval from `from` to a new state `to`; the point of `to` is the
  /// prediction from the point of `from`, moved by a random step unless
  /// `at_prediction` (then the factor's residual there is zero).
  Factor Dynamics(StateId from, StateId to, bool at_prediction, Values* point) {
    State& from_point = point->states.at(from);
    if (linear_) {
      point->states[to] = NearbyState(from_point, to, 0.1, random_);
      truth.states[to] = NearbyState(truth.states.at(from), to, 0.1, random_);
      return LinearFactor({{from, to}, {}}, 15, at_prediction);
    }
    const std::shared_ptr<const ImuPreintegration> imu = ImuInterval(truth.states.at(from), from_point, random_);
    truth.states[to] = Predict(truth.states.at(from), to, imu);
    point->states[to] = Predict(from_point, to, imu);
    if (!at_prediction) {
      Eigen::VectorXd step(15);
      step << random_->Normal(3) * 0.02, random_->Normal(3) * 0.01, random_->Normal(3) * 0.05,
          random_->Normal(3) * 0.001, random_->Normal(3) * 0.01;
      const Variables target{{to}, {}};
      point->Unstack(target, target.Layout().Plus(point->Stack(target), step));
    }
    return {Factor::Kind::kImu, {{from, to}, {}}, Eigen::Vector3d::Zero(), imu, {}, {}};
  }

  /// A new landmark in front of `s` (truth), at the point triangulated from
  /// its stereo measurement at the point of `seen_from` (moved by `offset_m`
  /// in each coordinate, so that its measurement keeps an innovation).
  void AddLandmark(LandmarkId l, const State& in_front_of, Values* point) {
    truth.landmarks[l] = LandmarkInFront(in_front_of, random_);
    point->landmarks[l] = truth.landmarks[l] + random_->Normal(3) * 0.1;
  }
  void TriangulateAt(LandmarkId l, StateId seen_from, double offset_m, Values* point) {
    if (linear_) return;
    const Eigen::Vector3d z = Project(truth.states.at(seen_from), truth.landmarks.at(l)) + random_->Normal(3);
    point->landmarks[l] = Triangulate(point->states.at(seen_from), z) + offset_m * random_->Normal(3);
  }

 private:
  Factor LinearFactor(const Variables& variables, int rows, bool zero_residual) {
    Factor f{Factor::Kind::kLinear, variables, Eigen::Vector3d::Zero(), nullptr, {}, {}};
    f.jacobian = kLinearScale * random_->Normal(rows, variables.TangentSize());
    // The block solved for (the later state of a dynamics factor, the landmark
    // of an observation) well conditioned, as the models' are.
    const int solved = variables.states.size() == 2 ? 15 : 3;
    f.jacobian.rightCols(solved) = kLinearScale * (3.0 * Eigen::MatrixXd::Identity(solved, solved) +
                                                   0.1 * random_->Normal(solved, solved));
    f.residual = zero_residual ? Eigen::VectorXd::Zero(rows) : random_->Normal(rows);
    return f;
  }

  bool linear_;
  Random* random_;
};

std::vector<LandmarkId> LandmarkIds(int first, int count) {
  std::vector<LandmarkId> ids;
  for (int k = 0; k < count; ++k) ids.push_back(LandmarkId{first + k});
  return ids;
}

/// A robot state (id 1) with p landmarks in front of it, as a prior.
Case EkfCase(Scene* scene, int p, Random* random) {
  Case c;
  const StateId x{1};
  scene->truth.states[x] = TrueState(x, random);
  c.prior_variables = {{x}, LandmarkIds(1, p)};
  for (LandmarkId l : c.prior_variables.landmarks) scene->truth.landmarks[l] = LandmarkInFront(scene->truth.states[x], random);
  c.prior = scene->Prior(c.prior_variables, &c.point);
  return c;
}

/// An IMU state (id 1) and n clones (ids 2..n+1) spread over the metre behind
/// it, as a prior (IMU state first).
Case MsckfCase(Scene* scene, int n, Random* random) {
  Case c;
  const StateId imu{1};
  const State first = TrueState(StateId{2}, random);
  scene->truth.states[imu] = NearbyState(first, imu, 1.2, random);
  scene->truth.states[imu].SetSpeedBias(first.v_w_b(), first.gyro_bias(), first.accel_bias());
  c.prior_variables.states.push_back(imu);
  for (int i = 0; i < n; ++i) {
    const StateId id{2 + i};
    scene->truth.states[id] = NearbyState(first, id, i * 1.0 / n, random);
    c.prior_variables.states.push_back(id);
  }
  c.prior = scene->Prior(c.prior_variables, &c.point);
  return c;
}

/// Features ids 1..p in front of `anchor`, each seen from 2..all of `from`.
void AddFeatures(Scene* scene, int p, const std::vector<StateId>& from, StateId anchor, Case* c, Random* random) {
  for (LandmarkId l : LandmarkIds(1, p)) {
    scene->AddLandmark(l, scene->truth.states.at(anchor), &c->point);
    const std::vector<int> seen = random->Subset(static_cast<int>(from.size()), random->Integer(2, static_cast<int>(from.size())));
    scene->TriangulateAt(l, from[seen.front()], 0.0, &c->point);
    for (int i : seen) c->factors.push_back(scene->Observation(from[i], l));
  }
}

}  // namespace

marginalization::StateLayout Variables::Layout() const {
  marginalization::StateLayout layout;
  for (size_t i = 0; i < states.size(); ++i) layout.AddManifold(&Manifold()).AddEuclidean(kSpeedBiasSize);
  for (size_t i = 0; i < landmarks.size(); ++i) layout.AddEuclidean(kLandmarkSize);
  return layout;
}

int Variables::Column(StateId id) const {
  const auto it = std::find(states.begin(), states.end(), id);
  if (it == states.end()) return -1;
  return kStateTangent * static_cast<int>(it - states.begin());
}

int Variables::Column(LandmarkId id) const {
  const auto it = std::find(landmarks.begin(), landmarks.end(), id);
  if (it == landmarks.end()) return -1;
  return kStateTangent * static_cast<int>(states.size()) + 3 * static_cast<int>(it - landmarks.begin());
}

Eigen::VectorXd Values::Stack(const Variables& variables) const {
  Eigen::VectorXd x(variables.Layout().AmbientSize());
  int k = 0;
  for (StateId id : variables.states) {
    const State& s = states.at(id);
    x.segment<kPoseSize>(k) = Eigen::Map<const Eigen::Matrix<double, kPoseSize, 1>>(s.pose);
    x.segment<kSpeedBiasSize>(k + kPoseSize) = Eigen::Map<const Eigen::Matrix<double, kSpeedBiasSize, 1>>(s.speed_bias);
    k += kStateAmbient;
  }
  for (LandmarkId id : variables.landmarks) {
    x.segment<3>(k) = landmarks.at(id);
    k += 3;
  }
  return x;
}

void Values::Unstack(const Variables& variables, const Eigen::VectorXd& x) {
  int k = 0;
  for (StateId id : variables.states) {
    State& s = states[id];
    s.id = id;
    Eigen::Map<Eigen::Matrix<double, kPoseSize, 1>>(s.pose) = x.segment<kPoseSize>(k);
    Eigen::Map<Eigen::Matrix<double, kSpeedBiasSize, 1>>(s.speed_bias) = x.segment<kSpeedBiasSize>(k + kPoseSize);
    k += kStateAmbient;
  }
  for (LandmarkId id : variables.landmarks) {
    landmarks[id] = x.segment<3>(k);
    k += 3;
  }
}

Eigen::VectorXd Values::FromWindow(const Window& window, const Variables& variables) {
  Values values;
  for (StateId id : variables.states) values.states[id] = window.state(id);
  for (LandmarkId id : variables.landmarks) values.landmarks[id] = window.landmark(id).position();
  return values.Stack(variables);
}

ModelOptions Model() {
  ModelOptions model;
  model.pixel_sigma = 1.0;
  model.huber_px = 0.0;
  return model;
}

RectifiedStereo Stereo() {
  RectifiedStereo stereo;
  Eigen::Matrix3d R_b_c;
  R_b_c << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // camera z along body x
  stereo.T_b_cl.linear() = R_b_c;
  stereo.T_b_cl.translation() = Eigen::Vector3d(0.05, -0.02, 0.01);
  return stereo;
}

Eigen::Vector3d Gravity() { return Eigen::Vector3d(0.0, 0.0, -Model().gravity); }

namespace {

/// The parameter blocks of a factor's variables at `values`, with manifolds.
struct Blocks {
  std::vector<double*> pointers;
  std::vector<int> sizes;  ///< ambient
  std::vector<const ceres::Manifold*> manifolds;
  std::vector<int> columns;  ///< tangent column in the caller's Variables, -1: not one of them
};

Blocks BlocksOf(const Factor& factor, Values* values, const Variables* columns) {
  Blocks b;
  const auto add = [&b](double* pointer, int size, const ceres::Manifold* manifold, int column) {
    b.pointers.push_back(pointer);
    b.sizes.push_back(size);
    b.manifolds.push_back(manifold);
    b.columns.push_back(column);
  };
  for (StateId id : factor.variables.states) {
    State& s = values->states.at(id);
    const int column = columns != nullptr ? columns->Column(id) : -1;
    add(s.pose, kPoseSize, &Manifold(), column);
    if (factor.kind == Factor::Kind::kStereo) continue;  // a stereo factor sees the pose only
    add(s.speed_bias, kSpeedBiasSize, nullptr, column < 0 ? -1 : column + 6);
  }
  for (LandmarkId id : factor.variables.landmarks) {
    add(values->landmarks.at(id).data(), kLandmarkSize, nullptr, columns != nullptr ? columns->Column(id) : -1);
  }
  return b;
}

}  // namespace

std::unique_ptr<ceres::CostFunction> CostFunction(const Factor& factor, const Values& values) {
  switch (factor.kind) {
    case Factor::Kind::kStereo:
      return std::unique_ptr<ceres::CostFunction>(StereoFactor::Create(factor.z_px, Stereo(), Model().pixel_sigma));
    case Factor::Kind::kImu:
      return std::unique_ptr<ceres::CostFunction>(ImuFactor::Create(*factor.preintegration, Gravity()));
    case Factor::Kind::kLinear: {
      Values copy = values;
      const Blocks blocks = BlocksOf(factor, &copy, nullptr);
      std::vector<marginalization::MarginalizationPrior::Block> prior_blocks;
      for (size_t i = 0; i < blocks.pointers.size(); ++i) {
        prior_blocks.push_back({blocks.manifolds[i], std::vector<double>(blocks.pointers[i], blocks.pointers[i] + blocks.sizes[i])});
      }
      return marginalization::MarginalizationPrior::Create(std::move(prior_blocks), factor.jacobian, factor.residual);
    }
  }
  throw std::logic_error("unknown factor kind");
}

Linearization Linearize(const std::vector<Factor>& factors, const Values& values, const Variables& columns) {
  Values at = values;
  std::vector<Eigen::VectorXd> e0s;
  std::vector<Eigen::MatrixXd> Js;
  int rows = 0;
  for (const Factor& factor : factors) {
    const std::unique_ptr<ceres::CostFunction> f = CostFunction(factor, at);
    const Blocks blocks = BlocksOf(factor, &at, &columns);
    const int m = f->num_residuals();
    Eigen::VectorXd e(m);
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> ambient;
    std::vector<double*> jacobians;
    for (const int size : f->parameter_block_sizes()) {
      ambient.emplace_back(m, size);
      jacobians.push_back(ambient.back().data());
    }
    if (!f->Evaluate(blocks.pointers.data(), e.data(), jacobians.data())) throw Error("a factor does not evaluate");
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, columns.TangentSize());
    for (size_t i = 0; i < blocks.pointers.size(); ++i) {
      if (blocks.columns[i] < 0) continue;  // held: not a column
      if (blocks.manifolds[i] == nullptr) {
        J.middleCols(blocks.columns[i], ambient[i].cols()) = ambient[i];
        continue;
      }
      Eigen::Matrix<double, kPoseSize, 6, Eigen::RowMajor> plus;
      blocks.manifolds[i]->PlusJacobian(blocks.pointers[i], plus.data());
      J.middleCols(blocks.columns[i], 6) = ambient[i] * plus;
    }
    e0s.push_back(e);
    Js.push_back(J);
    rows += m;
  }
  Linearization lin{Eigen::VectorXd(rows), Eigen::MatrixXd(rows, columns.TangentSize())};
  int row = 0;
  for (size_t k = 0; k < e0s.size(); ++k) {
    lin.e0.segment(row, e0s[k].size()) = e0s[k];
    lin.J.middleRows(row, Js[k].rows()) = Js[k];
    row += static_cast<int>(e0s[k].size());
  }
  return lin;
}

std::unique_ptr<Window> BuildWindow(const Case& c, const Window::FactorWrapper& wrap_first_factor) {
  auto window = std::make_unique<Window>(Model(), Stereo());
  for (const auto& [id, value] : c.point.states) {
    State& s = window->AddState(id, id.value * 100'000'000LL);
    std::copy(value.pose, value.pose + kPoseSize, s.pose);
    std::copy(value.speed_bias, value.speed_bias + kSpeedBiasSize, s.speed_bias);
  }
  for (const auto& [id, p_w] : c.point.landmarks) window->AddLandmark(id, p_w);
  const Eigen::LLT<Eigen::MatrixXd> llt(c.prior.covariance);
  const Eigen::MatrixXd sqrt_information =
      llt.matrixL().solve(Eigen::MatrixXd::Identity(c.prior.covariance.rows(), c.prior.covariance.cols()));
  window->AddLinearFactor(c.prior_variables.states, c.prior_variables.landmarks, sqrt_information,
                          Eigen::VectorXd::Zero(sqrt_information.rows()));
  for (size_t k = 0; k < c.factors.size(); ++k) {
    window->SetFactorWrapper(k == 0 ? wrap_first_factor : Window::FactorWrapper());
    const Factor& f = c.factors[k];
    switch (f.kind) {
      case Factor::Kind::kStereo:
        window->AddObservation(f.variables.states.front(), f.variables.landmarks.front(), f.z_px);
        break;
      case Factor::Kind::kImu:
        window->AddImuFactor(f.variables.states.front(), f.variables.states.back(), *f.preintegration);
        break;
      case Factor::Kind::kLinear:
        window->AddLinearFactor(f.variables.states, f.variables.landmarks, f.jacobian, f.residual);
        break;
    }
  }
  window->SetFactorWrapper({});
  return window;
}

CaseSet RandomCases(const std::string& kind, int p, int n, unsigned seed) {
  if (kind != "linear" && kind != "nonlinear") throw std::invalid_argument("window_cases: kind must be linear or nonlinear");
  if (p < 1 || p > 50 || n < 2 || n > 20) throw std::invalid_argument("window_cases: need p in [1, 50] and n in [2, 20]");
  Random random(seed);
  const bool linear = kind == "linear";
  CaseSet set;
  set.num_new_features = std::max(1, p / 2);
  {  // 4.3.1: new features ids p+1.. seen once from x, at their triangulation moved by 5 cm.
    Scene scene(linear, &random);
    Case c = EkfCase(&scene, p, &random);
    for (LandmarkId l : LandmarkIds(p + 1, set.num_new_features)) {
      scene.AddLandmark(l, scene.truth.states.at(StateId{1}), &c.point);
      scene.TriangulateAt(l, StateId{1}, 0.05, &c.point);
      c.factors.push_back(scene.Observation(StateId{1}, l));
    }
    set.ekf_augmentation = std::move(c);
  }
  {  // 4.3.2
    Scene scene(linear, &random);
    Case c = EkfCase(&scene, p, &random);
    for (LandmarkId l : c.prior_variables.landmarks) c.factors.push_back(scene.Observation(StateId{1}, l));
    set.ekf_update = std::move(c);
  }
  {  // 4.3.3: x_{t+1} (id 2) away from the prediction
    Scene scene(linear, &random);
    Case c = EkfCase(&scene, p, &random);
    c.factors.push_back(scene.Dynamics(StateId{1}, StateId{2}, /*at_prediction=*/false, &c.point));
    set.ekf_propagation = std::move(c);
  }
  {  // 4.3.4: features seen from the clones
    Scene scene(linear, &random);
    Case c = MsckfCase(&scene, n, &random);
    const std::vector<StateId> clones(c.prior_variables.states.begin() + 1, c.prior_variables.states.end());
    AddFeatures(&scene, p, clones, clones.front(), &c, &random);
    set.msckf_update = std::move(c);
  }
  {  // 4.3.5: the new IMU state id n + 2 away from the prediction
    Scene scene(linear, &random);
    Case c = MsckfCase(&scene, n, &random);
    c.factors.push_back(scene.Dynamics(StateId{1}, StateId{n + 2}, /*at_prediction=*/false, &c.point));
    set.msckf_propagation = std::move(c);
  }
  {  // Algorithm 3: x_t (id 2) at the prediction, the landmarks seen from it
    Scene scene(linear, &random);
    Case c = EkfCase(&scene, p, &random);
    c.factors.push_back(scene.Dynamics(StateId{1}, StateId{2}, /*at_prediction=*/true, &c.point));
    for (LandmarkId l : c.prior_variables.landmarks) c.factors.push_back(scene.Observation(StateId{2}, l));
    set.ekf_step = std::move(c);
  }
  {  // Algorithm 4: the new state id n + 2 at the prediction; features seen from the clones and it
    Scene scene(linear, &random);
    Case c = MsckfCase(&scene, n, &random);
    c.factors.push_back(scene.Dynamics(StateId{1}, StateId{n + 2}, /*at_prediction=*/true, &c.point));
    std::vector<StateId> from(c.prior_variables.states.begin() + 1, c.prior_variables.states.end());
    from.push_back(StateId{n + 2});
    AddFeatures(&scene, p, from, from.front(), &c, &random);
    set.msckf_step = std::move(c);
  }
  return set;
}

}  // namespace vio::tools::window_cases
