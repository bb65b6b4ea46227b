#pragma once
// `vio simulate`: synthetic and hybrid EuRoC-format datasets.
//
//  * synthetic: a smooth closed flight (trajectory.h) through a textured
//    room with clutter (scene.h), IMU synthesized from the analytic
//    trajectory with EuRoC noise (imu.h), the real EuRoC V2_01
//    calibration, camera frames at the camera rate.
//  * hybrid (from_euroc_dir set): the real IMU and calibration of an ASL
//    folder copied unchanged, its ground truth too but for glitches that
//    disagree with its own velocity (removed unless keep_groundtruth_jumps);
//    the cameras see the synthetic room along that ground truth
//    (interpolated at the real cam0 stamps; frames outside the ground truth
//    are dropped).
// The camera side is either feature tracks (features0/data.csv,
// features.h) or rendered stereo PNG images (cam0/cam1, render.h): surfaces
// textured with real images (texture.h), then exposed by a simulated sensor
// (sensor.h: auto exposure, motion blur along the true motion, vignetting,
// shot and read noise).
// Frames can be dropped and blacked out on purpose (gaps.h).
// Output is deterministic for a given seed.
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "vio/dataset/euroc_dataset.h"
#include "vio/simulator/features.h"
#include "vio/simulator/gaps.h"
#include "vio/simulator/imu.h"
#include "vio/simulator/render.h"
#include "vio/simulator/rig_errors.h"
#include "vio/simulator/rig_faults.h"
#include "vio/simulator/scene.h"
#include "vio/simulator/sensor.h"
#include "vio/simulator/texture.h"
#include "vio/simulator/trajectory.h"

namespace vio::tools {

enum class SimCameraOutput { kFeatures, kImages };

struct SimulatorOptions {
  /// Folder to write (the one that will hold mav0/); required by Simulate.
  std::string output_dir;
  /// ASL folder of a real sequence for hybrid mode; empty = synthetic.
  std::string from_euroc_dir;
  /// Hybrid mode: camera frames of the first this many seconds only (0: all), counted from
  /// from_start_s [s].
  double from_duration_s = 0.0;
  /// Hybrid mode: the sequence is cut this many seconds after its first camera frame (camera, IMU
  /// and ground truth), e.g. to start in flight [s]. The whole sequence is simulated and then cut, so
  /// from the cut on the features and their noise are those of the uncut sequence (same seeds).
  double from_start_s = 0.0;
  /// Hybrid mode: ground-truth steps that disagree with the ground truth's own
  /// velocity by more than 5 m/s (a glitch of the reference: EuRoC MH_04 has
  /// one of 14 cm in 5 ms) are removed (RemoveGroundTruthJumps: the cameras and
  /// the written ground truth move as the real IMU does) unless this is set
  /// (the cameras then jump with the ground truth, the real IMU does not).
  bool keep_groundtruth_jumps = false;
  /// What the cameras produce.
  SimCameraOutput camera_output = SimCameraOutput::kFeatures;
  /// Seed of every random draw (std::mt19937_64).
  std::uint64_t seed = 1;
  /// Seed of the measurement noise alone (IMU noise and biases, feature
  /// selection and pixel noise, rendered images' sensor noise) when not 0: the trajectory and the scene
  /// (from `seed`) stay the same, so runs with different noise seeds are
  /// Monte Carlo realizations of one experiment. 0 = every draw from `seed`.
  std::uint64_t noise_seed = 0;
  /// Synthetic flight length including the initial static period [s].
  double duration_s = 60.0;
  /// Room, clutter and landmarks.
  SceneOptions scene;
  /// Shape limits of the synthetic flight (centre and extents are derived
  /// from the room: centred, keeping flight_wall_clearance_m to the walls).
  SyntheticTrajectoryOptions trajectory;
  /// Horizontal distance the synthetic flight keeps to the walls [m].
  double flight_wall_clearance_m = 1.5;
  /// Synthetic IMU rate, noise densities and initial biases (defaults: EuRoC imu0).
  ImuSynthesisOptions imu;
  /// Feature tracks (features mode).
  FeatureSimOptions features;
  /// Dropped frames and blackouts (none by default).
  FrameGapOptions gaps;
  /// Camera-IMU time offset and extrinsic error written into the dataset (none by default;
  /// rig_errors.h): the cameras are simulated with the true rig.
  RigErrorOptions rig;
  /// Image rendering (images mode; texture seed derived from `seed`;
  /// the noise is the sensor's).
  RenderOptions render;
  /// Real images the surfaces are textured with (images mode).
  ImageTextureOptions textures;
  /// Exposure, motion blur, vignetting and noise of the cameras (images mode).
  SensorOptions sensor;
  /// PNG compression level 0..9 of rendered images. 0 stores the pixels
  /// uncompressed, as EuRoC's own PNGs are; noisy renderings shrink only to
  /// about 0.6 of that at level 1, and take twice as long to decode.
  int png_compression = 0;
  /// Measurements written wrong on purpose (IMU units, swapped cameras); none by default.
  RigFaults faults;
};

/// Everything simulated, in memory.
struct Simulation {
  EurocDataset dataset;            ///< what WriteEuroc writes (features when in features mode)
  Scene scene;                     ///< the world; landmark index = feature_id
  std::vector<FramePose> frames;   ///< body pose at each camera frame
  FeatureSimulation features;      ///< per-frame counts and track lengths (features mode)
  std::vector<GroundTruthJump> groundtruth_jumps;  ///< hybrid: the source ground truth's jumps (removed unless kept)
  /// The path the room and landmarks are built around: the whole ground truth, also when the
  /// sequence is cut (from_start_s), so a cut sequence flies through the same world.
  std::vector<Eigen::Vector3d> scene_path;
  /// from_start_s: the first kept time; the whole sequence is simulated, then cut there.
  std::optional<Timestamp> cut_ns;
};

struct SimulationSummary {
  bool hybrid = false;
  SimCameraOutput camera_output = SimCameraOutput::kFeatures;
  int frames = 0;
  int imu_samples = 0;
  int landmarks = 0;
  double features_per_frame = 0.0;         ///< cam0 observations per frame
  double stereo_features_per_frame = 0.0;  ///< landmarks seen in both cameras per frame
  double median_track_length = 0.0;        ///< [frames]
  int groundtruth_jumps = 0;               ///< hybrid: jumps found in the source ground truth
  bool groundtruth_jumps_kept = false;     ///< ... and left in (keep_groundtruth_jumps)
  double seconds = 0.0;                    ///< wall time [s]
};

/// The EuRoC V2_01 calibration (cam0, cam1: pinhole radial-tangential,
/// 752 x 480, 20 Hz, real T_BS) used in synthetic mode.
std::array<CameraCalibration, 2> EurocStereoCalibration();

/// Simulates in memory (features computed in features mode; images are not
/// rendered here). Throws std::invalid_argument on bad options and
/// DatasetError when the hybrid source cannot be read.
Simulation BuildSimulation(const SimulatorOptions& options);

/// Told how many of `total` images are written, after each one (images mode).
using RenderProgress = std::function<void(std::int64_t done, std::int64_t total)>;

/// Writes the ASL folder (WriteEuroc), the scene's geometry as mav0/scene.csv
/// (scene_csv.h) and, in images mode, renders and
/// writes cam0/cam1 PNGs, calling `progress` (when set) after each image.
/// Throws std::invalid_argument on an empty output_dir, std::runtime_error
/// when an image cannot be written.
void WriteSimulation(const Simulation& simulation, const SimulatorOptions& options,
                     const RenderProgress& progress = {});

/// BuildSimulation + WriteSimulation, timed.
SimulationSummary Simulate(const SimulatorOptions& options, const RenderProgress& progress = {});

/// One paragraph for the command line.
std::string FormatSummary(const SimulationSummary& summary, const std::string& output_dir);

}  // namespace vio::tools
