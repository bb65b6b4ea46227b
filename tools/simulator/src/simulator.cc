#include "vio/simulator/simulator.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <glog/logging.h>
#include <opencv2/imgcodecs.hpp>

#include "vio/dataset/image_file.h"
#include "vio/dataset/scene_csv.h"

namespace vio::tools {
namespace {

/// Start of the synthetic clock (an arbitrary epoch) [ns].
constexpr Timestamp kSyntheticStartNs = 1'600'000'000'000'000'000;

/// A ground-truth step further than this from its own velocity is reported as
/// a jump [m/s]: 2.5 cm in one 5 ms sample, above the sample noise of the
/// EuRoC references (MH_04's laser-tracker positions reach 2 m/s).
constexpr double kMaxGroundTruthVelocityMismatch = 5.0;

/// Grey level of a rendered frame during a blackout (a covered lens).
constexpr int kBlackoutGrey = 4;

Eigen::Isometry3d FromRowMajor(const std::array<double, 12>& m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = m[4 * r + c];
  }
  return T;
}

void CheckOptions(const SimulatorOptions& options) {
  if (options.from_euroc_dir.empty() && !(options.duration_s > 0.0)) {
    throw std::invalid_argument("simulator: duration must be positive, got " +
                                std::to_string(options.duration_s) + " s");
  }
  if (!(options.from_start_s >= 0.0)) {
    throw std::invalid_argument("simulator: from_start_s must be >= 0, got " + std::to_string(options.from_start_s));
  }
  if (!(options.from_duration_s >= 0.0)) {
    throw std::invalid_argument("simulator: from_duration_s must be >= 0 (0: the whole sequence), got " +
                                std::to_string(options.from_duration_s));
  }
  CheckSensorOptions(options.sensor);
  CheckImageTextureOptions(options.textures);
  CheckRigFaults(options.faults);
  CheckRigErrorOptions(options.rig);
  if (options.png_compression < 0 || options.png_compression > 9) {
    throw std::invalid_argument("simulator: PNG compression must be in 0..9, got " +
                                std::to_string(options.png_compression));
  }
}

// The flight is centred in the nominal room and keeps the clearance to its walls.
SyntheticTrajectoryOptions FlightInRoom(const SimulatorOptions& options) {
  const SceneOptions& scene = options.scene;
  SyntheticTrajectoryOptions flight = options.trajectory;
  const double floor_z = scene.room_center_m.z() - 0.5 * scene.room_size_m.z();
  flight.center_w = Eigen::Vector3d(scene.room_center_m.x(), scene.room_center_m.y(),
                                    floor_z + 0.4 * scene.room_size_m.z());
  flight.half_extent_m = Eigen::Vector3d(0.5 * scene.room_size_m.x() - options.flight_wall_clearance_m,
                                         0.5 * scene.room_size_m.y() - options.flight_wall_clearance_m,
                                         0.2 * scene.room_size_m.z());
  if (flight.half_extent_m.minCoeff() < 0.1) {
    throw std::invalid_argument(
        "simulator: room too small for the synthetic flight (room size minus twice the wall clearance "
        "must be at least 0.2 m in x and y)");
  }
  return flight;
}

std::vector<CameraFrame> FrameRows(const std::vector<FramePose>& frames) {
  std::vector<CameraFrame> rows;
  for (const FramePose& f : frames) rows.push_back({f.t_ns, std::to_string(f.t_ns) + ".png"});
  return rows;
}

std::vector<Eigen::Vector3d> PathOf(const std::vector<GroundTruthState>& groundtruth) {
  std::vector<Eigen::Vector3d> path;
  for (const GroundTruthState& s : groundtruth) path.push_back(s.p_w_b);
  return path;
}

void BuildSyntheticMotion(const SimulatorOptions& options, std::mt19937_64* rng, Simulation* sim) {
  const SyntheticTrajectory trajectory(FlightInRoom(options));
  ImuSynthesis imu = SynthesizeImu(trajectory, kSyntheticStartNs, options.duration_s, options.imu, rng);
  EurocDataset& dataset = sim->dataset;
  dataset.imu_calibration = options.imu.calibration;
  dataset.imu = std::move(imu.imu);
  dataset.groundtruth = std::move(imu.groundtruth);
  const std::array<CameraCalibration, 2> cameras = EurocStereoCalibration();
  dataset.cameras[0] = cameras[0];
  dataset.cameras[1] = cameras[1];
  const Timestamp period_ns = SecondsToNanos(1.0 / cameras[0].rate_hz);
  for (Timestamp offset_ns = 0; offset_ns <= SecondsToNanos(options.duration_s); offset_ns += period_ns) {
    const KinematicState state = trajectory.Evaluate(NanosToSeconds(offset_ns));
    FramePose frame;
    frame.t_ns = kSyntheticStartNs + offset_ns;
    frame.T_w_b.linear() = state.q_w_b.toRotationMatrix();
    frame.T_w_b.translation() = state.p_w_b;
    sim->frames.push_back(frame);
  }
}

// One warning per jump of the source ground truth, saying what became of it.
void WarnOfGroundTruthJumps(const SimulatorOptions& options, const std::vector<GroundTruthJump>& jumps) {
  for (const GroundTruthJump& jump : jumps) {
    std::ostringstream what;
    what << std::fixed << std::setprecision(3) << options.from_euroc_dir << ": the ground truth jumps " << jump.step_m
         << " m at t=" << NanosToSeconds(jump.t_ns) << " s (" << jump.speed_m_s << " m/s against its velocity of "
         << jump.velocity_m_s << " m/s); ";
    if (options.keep_groundtruth_jumps) {
      what << "kept: the simulated cameras follow the jump, the real IMU does not";
    } else {
      what << "removed: from then on the ground truth (the cameras' and the written one) is moved back by the "
           << jump.excess_m.norm() << " m its velocity does not explain";
    }
    LOG(WARNING) << what.str();
  }
}

// Index of the last sample at or before t_ns (0 when none): what is kept
// from there on covers the first frame at or after t_ns.
template <class Sample>
std::ptrdiff_t FirstKept(Timestamp t_ns, const std::vector<Sample>& samples) {
  auto it = std::lower_bound(samples.begin(), samples.end(), t_ns,
                             [](const Sample& s, Timestamp t) { return s.t_ns < t; });
  if (it != samples.begin() && (it == samples.end() || it->t_ns > t_ns)) --it;
  return it - samples.begin();
}

// The IMU and ground truth before the cut are removed.
void CutHybridStart(Timestamp t_ns, EurocDataset* dataset) {
  if (dataset->frames[0].back().t_ns < t_ns) {
    throw std::invalid_argument("simulator: from_start_s is past the sequence's last camera frame");
  }
  const std::ptrdiff_t imu_kept = FirstKept(t_ns, dataset->imu);
  if (dataset->imu_lines.size() == dataset->imu.size()) {
    dataset->imu_lines.erase(dataset->imu_lines.begin(), dataset->imu_lines.begin() + imu_kept);
  }
  dataset->imu.erase(dataset->imu.begin(), dataset->imu.begin() + imu_kept);
  dataset->groundtruth.erase(dataset->groundtruth.begin(),
                             dataset->groundtruth.begin() + FirstKept(t_ns, dataset->groundtruth));
}

void BuildHybridMotion(const SimulatorOptions& options, Simulation* sim) {
  EurocReadOptions read;
  read.read_features = false;
  read.check_images = false;
  EurocDataset& dataset = sim->dataset;
  dataset = ReadEuroc(options.from_euroc_dir, read);
  if (dataset.groundtruth.empty() || dataset.frames[0].empty()) {
    throw DatasetError(options.from_euroc_dir + ": hybrid mode needs ground truth and cam0/data.csv");
  }
  sim->groundtruth_jumps = FindGroundTruthJumps(dataset.groundtruth, kMaxGroundTruthVelocityMismatch);
  WarnOfGroundTruthJumps(options, sim->groundtruth_jumps);
  if (!options.keep_groundtruth_jumps) {
    dataset.groundtruth = RemoveGroundTruthJumps(std::move(dataset.groundtruth), sim->groundtruth_jumps);
  }
  dataset.root.clear();
  dataset.features.clear();
  dataset.has_images = false;
  sim->scene_path = PathOf(dataset.groundtruth);
  // A cut sequence is the whole sequence's simulation with its start removed (CutFramesBefore): the frames
  // before the cut are simulated too, so every draw from the cut on is the one the whole sequence gets.
  const Timestamp first_ns = dataset.frames[0].front().t_ns + SecondsToNanos(options.from_start_s);
  if (options.from_start_s > 0.0 && dataset.frames[0].back().t_ns < first_ns) {
    throw std::invalid_argument("simulator: from_start_s is past the sequence's last camera frame");
  }
  for (const CameraFrame& row : dataset.frames[0]) {
    if (options.from_duration_s > 0.0 && row.t_ns - first_ns > SecondsToNanos(options.from_duration_s)) break;
    if (const std::optional<Eigen::Isometry3d> T_w_b = InterpolatePose(dataset.groundtruth, row.t_ns)) {
      sim->frames.push_back({row.t_ns, *T_w_b});
    }
  }
  if (options.from_start_s > 0.0) sim->cut_ns = first_ns;
}

// from_start_s: the frames before the cut, their features, IMU and ground truth are removed.
void CutFramesBefore(Timestamp t_ns, Simulation* sim) {
  CutHybridStart(t_ns, &sim->dataset);
  std::size_t kept = 0;
  while (kept < sim->frames.size() && sim->frames[kept].t_ns < t_ns) ++kept;
  sim->frames.erase(sim->frames.begin(), sim->frames.begin() + kept);
  for (std::vector<CameraFrame>& rows : sim->dataset.frames) {
    rows.erase(rows.begin(), std::lower_bound(rows.begin(), rows.end(), t_ns,
                                              [](const CameraFrame& f, Timestamp t) { return f.t_ns < t; }));
  }
  FeatureSimulation& features = sim->features;
  for (std::vector<int>* counts : {&features.cam0_count, &features.stereo_count}) {
    counts->erase(counts->begin(), counts->begin() + std::min(kept, counts->size()));
  }
  std::vector<FeatureObservation>& obs = features.observations;
  obs.erase(std::remove_if(obs.begin(), obs.end(), [t_ns](const FeatureObservation& o) { return o.t_ns < t_ns; }),
            obs.end());
  sim->dataset.features = obs;
}

// Features seen during a blackout are removed (and their per-frame counts).
void BlackOutFeatures(const std::vector<Blackout>& blackouts, Timestamp first_frame_ns, Simulation* sim) {
  ApplyBlackouts(blackouts, first_frame_ns, &sim->features.observations);
  for (std::size_t i = 0; i < sim->frames.size() && i < sim->features.cam0_count.size(); ++i) {
    if (BlackoutAt(sim->frames[i].t_ns, first_frame_ns, blackouts) < 0) continue;
    sim->features.cam0_count[i] = 0;
    sim->features.stereo_count[i] = 0;
  }
}

SimulationSummary Summarize(const Simulation& sim, const SimulatorOptions& options) {
  SimulationSummary summary;
  summary.hybrid = !options.from_euroc_dir.empty();
  summary.camera_output = options.camera_output;
  summary.frames = static_cast<int>(sim.frames.size());
  summary.imu_samples = static_cast<int>(sim.dataset.imu.size());
  summary.landmarks = static_cast<int>(sim.scene.landmarks.size());
  const std::vector<int>& cam0 = sim.features.cam0_count;
  const std::vector<int>& stereo = sim.features.stereo_count;
  if (!cam0.empty()) {
    summary.features_per_frame = std::accumulate(cam0.begin(), cam0.end(), 0.0) / cam0.size();
    summary.stereo_features_per_frame = std::accumulate(stereo.begin(), stereo.end(), 0.0) / stereo.size();
  }
  summary.median_track_length = MedianTrackLength(sim.features);
  summary.groundtruth_jumps = static_cast<int>(sim.groundtruth_jumps.size());
  summary.groundtruth_jumps_kept = options.keep_groundtruth_jumps;
  return summary;
}

// The poses of camera `camera` during the exposure of frame i (see ExposurePoses).
std::vector<Eigen::Isometry3d> CameraExposurePoses(const Simulation& sim, std::size_t i, const CameraCalibration& camera,
                                                   double exposure_s, const SensorOptions& sensor) {
  const FramePose& frame = sim.frames[i];
  auto pose_at = [&](double offset_s) -> std::optional<Eigen::Isometry3d> {
    if (offset_s == 0.0) return frame.T_w_b * camera.T_b_c;
    const std::optional<Eigen::Isometry3d> T_w_b =
        InterpolatePose(sim.dataset.groundtruth, frame.t_ns + SecondsToNanos(offset_s));
    if (!T_w_b) return std::nullopt;
    return *T_w_b * camera.T_b_c;
  };
  return ExposurePoses(pose_at, exposure_s, camera.intrinsics[0], sensor);
}

void WriteImages(const Simulation& sim, const SimulatorOptions& options, const RenderProgress& progress) {
  const std::vector<int> png = {cv::IMWRITE_PNG_COMPRESSION, options.png_compression};
  RenderOptions render = options.render;
  render.texture_seed = options.seed;
  const ImageTextures textures = LoadImageTextures(options.textures);
  const std::int64_t total = 2 * static_cast<std::int64_t>(sim.frames.size());
  // The sensor noise is measurement noise: --noise_seed draws it when given.
  const std::uint64_t image_noise_seed = options.noise_seed != 0 ? options.noise_seed : options.seed;
  cv::Mat radiance, image;
  for (int k = 0; k < 2; ++k) {
    const CameraCalibration& camera = sim.dataset.cameras[k];
    const SceneRenderer renderer(sim.scene, camera, render, &textures);
    const cv::Mat vignette = VignettingMap(camera, options.sensor.vignetting);
    const std::string folder = options.output_dir + "/mav0/cam" + std::to_string(k) + "/data";
    std::filesystem::create_directories(folder);
    for (std::size_t i = 0; i < sim.frames.size(); ++i) {
      const double brightness =
          ExposureFactor(options.sensor, options.seed, NanosToSeconds(sim.frames[i].t_ns - sim.frames.front().t_ns));
      const double exposure_s = 1e-3 * options.sensor.exposure_ms * brightness;
      const std::vector<Eigen::Isometry3d> poses = CameraExposurePoses(sim, i, camera, exposure_s, options.sensor);
      radiance.setTo(0.0f);
      for (const Eigen::Isometry3d& T_w_c : poses) {
        renderer.AddRadiance(T_w_c, 1.0f / static_cast<float>(poses.size()), &radiance);
      }
      ExposeImage(radiance, brightness, vignette, options.sensor, image_noise_seed * 1'000'003ULL + 2 * i + k, &image);
      if (BlackoutAt(sim.frames[i].t_ns, sim.frames.front().t_ns, options.gaps.blackouts) >= 0) {
        image.setTo(cv::Scalar::all(kBlackoutGrey));
      }
      const std::string path = folder + "/" + sim.dataset.frames[k][i].filename;
      if (!ImageWrite(path, image, png)) throw std::runtime_error("simulator: cannot write image " + path);
      if (progress) progress(static_cast<std::int64_t>(k * sim.frames.size() + i + 1), total);
    }
  }
}

}  // namespace

std::array<CameraCalibration, 2> EurocStereoCalibration() {
  std::array<CameraCalibration, 2> cameras;
  cameras[0].intrinsics = Eigen::Vector4d(458.654, 457.296, 367.215, 248.375);
  cameras[0].distortion = Eigen::Vector4d(-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05);
  cameras[0].T_b_c = FromRowMajor({0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
                                   0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
                                   -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949});
  cameras[1].intrinsics = Eigen::Vector4d(457.587, 456.134, 379.999, 255.238);
  cameras[1].distortion = Eigen::Vector4d(-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05);
  cameras[1].T_b_c = FromRowMajor({0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,
                                   0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,
                                   -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038});
  return cameras;
}

Simulation BuildSimulation(const SimulatorOptions& options) {
  CheckOptions(options);
  std::mt19937_64 rng(options.seed);
  std::mt19937_64 own_noise_rng(options.noise_seed);
  std::mt19937_64* noise_rng = options.noise_seed != 0 ? &own_noise_rng : &rng;
  Simulation sim;
  if (options.from_euroc_dir.empty()) {
    BuildSyntheticMotion(options, noise_rng, &sim);
  } else {
    BuildHybridMotion(options, &sim);
  }
  const Timestamp first_frame_ns = sim.frames.empty() ? 0 : sim.frames.front().t_ns;
  std::mt19937_64 gap_rng(options.seed ^ 0x6761707300000000ULL);  // own stream: other draws do not move
  sim.frames = DropFrames(sim.frames, options.gaps, &gap_rng);
  sim.dataset.frames[0] = FrameRows(sim.frames);
  sim.dataset.frames[1] = sim.dataset.frames[0];
  if (sim.scene_path.empty()) sim.scene_path = PathOf(sim.dataset.groundtruth);
  sim.scene = BuildScene(options.scene, sim.scene_path, &rng);
  if (options.camera_output == SimCameraOutput::kFeatures) {
    sim.features = SimulateFeatures(sim.scene, {sim.dataset.cameras[0], sim.dataset.cameras[1]}, sim.frames,
                                    options.features, noise_rng);
    BlackOutFeatures(options.gaps.blackouts, first_frame_ns, &sim);
    sim.dataset.features = sim.features.observations;
  }
  if (sim.cut_ns) CutFramesBefore(*sim.cut_ns, &sim);
  return sim;
}

void WriteSimulation(const Simulation& simulation, const SimulatorOptions& options,
                     const RenderProgress& progress) {
  if (options.output_dir.empty()) throw std::invalid_argument("simulator: an output folder is required");
  WriteSceneCsv({simulation.scene.room, simulation.scene.boxes}, options.output_dir + "/mav0/scene.csv");
  WriteRigTruth(options.rig, options.seed, options.output_dir + "/mav0/rig_truth.yaml");
  if (!options.faults.any() && !options.rig.any()) {
    WriteEuroc(simulation.dataset, options.output_dir);
    if (options.camera_output == SimCameraOutput::kImages) WriteImages(simulation, options, progress);
    return;
  }
  // Measured with the true rig; written with the faults (measurements) and rig errors (stamps, T_BS).
  Simulation faulty = simulation;
  ApplyRigFaults(options.faults, &faulty.dataset);
  EurocDataset written = faulty.dataset;
  ApplyRigErrors(options.rig, options.seed, &written);
  WriteEuroc(written, options.output_dir);
  if (options.faults.swap_cameras) std::swap(faulty.dataset.cameras[0], faulty.dataset.cameras[1]);
  if (options.camera_output == SimCameraOutput::kImages) WriteImages(faulty, options, progress);
}

SimulationSummary Simulate(const SimulatorOptions& options, const RenderProgress& progress) {
  const auto start = std::chrono::steady_clock::now();
  if (options.output_dir.empty()) throw std::invalid_argument("simulator: an output folder is required");
  const Simulation simulation = BuildSimulation(options);
  WriteSimulation(simulation, options, progress);
  SimulationSummary summary = Summarize(simulation, options);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

std::string FormatSummary(const SimulationSummary& summary, const std::string& output_dir) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(1);
  os << "simulated a " << (summary.hybrid ? "hybrid" : "synthetic") << " sequence: " << summary.frames
     << " stereo frames, " << summary.imu_samples << " IMU samples, " << summary.landmarks << " landmarks; ";
  if (summary.camera_output == SimCameraOutput::kFeatures) {
    os << summary.features_per_frame << " features per frame (" << summary.stereo_features_per_frame
       << " seen in both cameras), median track length " << summary.median_track_length << " frames; ";
  } else {
    os << 2 * summary.frames << " images rendered; ";
  }
  if (summary.groundtruth_jumps > 0) {
    os << summary.groundtruth_jumps << " ground-truth jump" << (summary.groundtruth_jumps > 1 ? "s " : " ")
       << (summary.groundtruth_jumps_kept ? "kept" : "removed") << "; ";
  }
  os << "took " << summary.seconds << " s; wrote " << output_dir << "\n";
  return os.str();
}

}  // namespace vio::tools
