// `vio simulate`: writes a synthetic or hybrid EuRoC ASL folder.
#include <cmath>
#include <cstdint>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/cli/progress.h"
#include "vio/simulator/simulator.h"

DEFINE_string(from, "", "hybrid mode: real EuRoC ASL folder whose IMU, ground truth and calibration are used");
DEFINE_double(from_duration_s, 0.0, "hybrid mode: only the camera frames of the first S seconds of the sequence "
              "(0: all) [s]");
DEFINE_double(from_start_s, 0.0, "hybrid mode: cut the sequence S seconds after its first camera frame (camera, "
              "IMU and ground truth), e.g. to start in flight; from the cut on, the same measurements as the whole "
              "sequence's simulation with the same seeds [s]");
DEFINE_double(flight_start_s, 0.0, "synthetic: how far along the flight t = 0 is: 0 starts at rest (the 3 s static "
              "start, then a 2 s ramp), 5 or more starts at full pace [s]");
DEFINE_string(groundtruth_jumps, "remove", "hybrid mode: ground-truth steps that disagree with its own velocity by "
              "more than 5 m/s (EuRoC MH_04 has one of 14 cm in 5 ms at 45 s): remove (the ground truth from then on "
              "is moved back by what its velocity does not explain, so the cameras move as the real IMU does; the "
              "written ground truth too) or keep (the cameras jump, the real IMU does not) {remove|keep}");
DEFINE_string(camera, "features", "camera output: features (features0/data.csv) or images (cam0/cam1 PNGs)");
DEFINE_uint64(seed, 1, "seed of every random draw; same seed, byte-identical output");
DEFINE_uint64(noise_seed, 0,
              "seed of the measurement noise alone (IMU noise and biases, features and their pixel noise, rendered "
              "images' sensor noise) when not 0: same --seed, same trajectory, scene and textures (Monte Carlo "
              "runs); 0 = every draw from --seed");
DEFINE_double(duration_s, 60.0, "synthetic flight length including the 3 s static start [s]");
DEFINE_double(pixel_noise, 0.5, "feature pixel noise, standard deviation per coordinate [px]");
DEFINE_double(outlier_rate, 0.0, "probability that a feature observation is a random pixel [0, 1]");
DEFINE_int32(max_features, 150, "feature budget per frame (cam0 tracks)");
DEFINE_string(room_size, "8,8,4", "room extent x,y,z [m] (grown to enclose a hybrid trajectory)");
DEFINE_double(room_margin, 0.3, "the room grows until the trajectory keeps this distance to every wall, the floor "
              "and the ceiling (hybrid trajectories that leave the --room_size room) [m]");
DEFINE_double(landmark_density, 10.0, "landmarks per square metre of wall, floor, ceiling and box");
DEFINE_int32(num_boxes, 8, "clutter boxes on the floor");
DEFINE_double(min_range, 0.25, "nearest observable landmark [m]");
DEFINE_double(max_range, 20.0, "farthest observable landmark [m]");
DEFINE_double(max_speed, 2.0, "synthetic flight speed limit [m/s]");
DEFINE_double(max_rotation_rate, 1.5, "synthetic flight angular rate limit [rad/s]");
DEFINE_double(sim_imu_noise, 1.0, "synthetic IMU noise and bias random walk, times the EuRoC densities");
DEFINE_string(texture_dir, "../shared/data/euroc/V1_01_easy_micro,../shared/data/euroc/V1_01_easy_flight10",
              "rendered images: folders of real grey images (an ASL folder: its cam0) the surfaces are textured "
              "with, read in place, comma-separated; none found: procedural textures with a warning; empty: "
              "procedural");
DEFINE_double(texel_size, 0.006, "rendered images: size of one texture image pixel on a surface [m]");
DEFINE_double(exposure_ms, 5.0, "rendered images: nominal exposure time, the motion blur integrates the true "
              "motion over it (0: no blur) [ms]");
DEFINE_double(exposure_variation, 0.25, "rendered images: auto-exposure changes, exposure time and brightness "
              "vary smoothly by up to a factor exp(+-this) [ln factor]");
DEFINE_double(exposure_period, 8.0, "rendered images: period of the slowest exposure change [s]");
DEFINE_int32(max_blur_samples, 12, "rendered images: most sub-frames integrated per exposure, spaced <= 0.5 px "
             "of image motion apart (1: no motion blur)");
DEFINE_double(vignetting, 0.3, "rendered images: brightness loss at the farthest image corner [0, 1)");
DEFINE_double(image_noise, 1.0, "rendered images: read noise, standard deviation [grey levels]");
DEFINE_double(shot_noise, 1.5, "rendered images: shot noise at grey 128, standard deviation [grey levels] "
              "(variance proportional to the signal)");
DEFINE_int32(png_compression, 0, "PNG compression level of rendered images, 0..9 (0: stored uncompressed, as "
             "EuRoC's PNGs are, the fastest to decode; 1-9: smaller files, twice the decoding time)");
DEFINE_double(drop_frames, 0.0, "fraction of the camera frames removed, in gaps placed by --drop_pattern [0, 1)");
DEFINE_int32(drop_gap_frames, 1,
             "--drop_pattern=even: consecutive frames removed per gap (1 at 20 Hz: 100 ms gaps); burst: the longest "
             "burst");
DEFINE_string(drop_pattern, "even",
              "where dropped frames go: even (gaps of exactly --drop_gap_frames, evenly spread) or burst (bursts of "
              "1 to --drop_gap_frames frames, more where the camera rotates fast, as real recordings drop them; e.g. "
              "--drop_frames=0.2 --drop_gap_frames=3 --drop_pattern=burst) {even|burst}");
DEFINE_string(imu_gyro_units, "rad_s", "imu0/data.csv's gyro written in these units, a user's mistake on purpose "
              "(sensor.yaml stays right): rad_s (right) or deg_s {rad_s|deg_s}");
DEFINE_string(imu_accel_units, "m_s2", "imu0/data.csv's accelerometer written in these units, a user's mistake on "
              "purpose: m_s2 (right) or g {m_s2|g}");
DEFINE_bool(swap_cameras, false, "write cam0's measurements (features' camera column, images) as cam1's and back, "
            "the calibration unchanged: a user's mistake on purpose");
DEFINE_double(time_offset_ms, 0.0, "rig error: camera stamps (cam0/cam1 data.csv, features0) written this much later "
              "than the IMU time the images were taken at; an image stamped t was taken at IMU time t - offset [ms]");
DEFINE_double(extrinsic_error_deg, 0.0, "rig error: both cameras' T_BS in sensor.yaml rotated by this in the body "
              "(the cameras are simulated with the true rig; the baseline is kept) [deg]");
DEFINE_double(extrinsic_error_m, 0.0, "rig error: both cameras' T_BS in sensor.yaml moved by this in the body [m]");
DEFINE_string(extrinsic_error_axis, "", "rig error: the rotation axis x,y,z in the body (empty: drawn from --seed)");
DEFINE_string(extrinsic_error_direction, "",
              "rig error: the translation direction x,y,z in the body (empty: drawn from --seed)");
DEFINE_string(blackouts, "", "spans with nothing to track, START:DURATION[,...] in s after the first frame: "
              "no features, black images");

namespace vio::tools {
namespace {

Eigen::Vector3d ParseVector3(const std::string& flag, const std::string& text) {
  std::vector<double> values;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(value)) {
      throw std::invalid_argument("--" + flag + ": '" + item + "' is not a number (expected x,y,z)");
    }
    values.push_back(value);
  }
  if (values.size() != 3) {
    throw std::invalid_argument("--" + flag + "=" + text + ": expected three comma-separated numbers x,y,z");
  }
  return Eigen::Vector3d(values[0], values[1], values[2]);
}

SimCameraOutput ParseCameraOutput(const std::string& text) {
  if (text == "features") return SimCameraOutput::kFeatures;
  if (text == "images") return SimCameraOutput::kImages;
  throw std::invalid_argument("--camera=" + text + ": expected 'features' or 'images'");
}

bool ParseKeepJumps(const std::string& text) {
  if (text == "remove") return false;
  if (text == "keep") return true;
  throw std::invalid_argument("--groundtruth_jumps=" + text + ": expected 'remove' or 'keep'");
}

SimulatorOptions OptionsFromFlags() {
  SimulatorOptions options;
  options.output_dir = FLAGS_output_dir;
  options.from_euroc_dir = FLAGS_from;
  options.from_duration_s = FLAGS_from_duration_s;
  options.from_start_s = FLAGS_from_start_s;
  options.trajectory.start_offset_s = FLAGS_flight_start_s;
  options.keep_groundtruth_jumps = ParseKeepJumps(FLAGS_groundtruth_jumps);
  options.camera_output = ParseCameraOutput(FLAGS_camera);
  options.seed = FLAGS_seed;
  options.noise_seed = FLAGS_noise_seed;
  options.duration_s = FLAGS_duration_s;
  options.features.pixel_noise_px = FLAGS_pixel_noise;
  options.features.outlier_rate = FLAGS_outlier_rate;
  options.features.max_features = FLAGS_max_features;
  options.features.min_range_m = FLAGS_min_range;
  options.features.max_range_m = FLAGS_max_range;
  options.scene.room_size_m = ParseVector3("room_size", FLAGS_room_size);
  options.scene.trajectory_margin_m = FLAGS_room_margin;
  options.scene.landmark_density_per_m2 = FLAGS_landmark_density;
  options.scene.num_boxes = FLAGS_num_boxes;
  options.trajectory.max_speed_m_s = FLAGS_max_speed;
  options.trajectory.max_rotation_rate_rad_s = FLAGS_max_rotation_rate;
  options.imu.noise_scale = FLAGS_sim_imu_noise;
  options.render.image_noise_sigma = FLAGS_image_noise;
  options.textures.dirs = FLAGS_texture_dir;
  options.textures.texel_m = FLAGS_texel_size;
  options.sensor.exposure_ms = FLAGS_exposure_ms;
  options.sensor.exposure_variation = FLAGS_exposure_variation;
  options.sensor.exposure_period_s = FLAGS_exposure_period;
  options.sensor.max_blur_samples = FLAGS_max_blur_samples;
  options.sensor.vignetting = FLAGS_vignetting;
  options.sensor.read_noise = FLAGS_image_noise;
  options.sensor.shot_noise = FLAGS_shot_noise;
  options.png_compression = FLAGS_png_compression;
  options.gaps.drop_fraction = FLAGS_drop_frames;
  options.gaps.gap_frames = FLAGS_drop_gap_frames;
  options.gaps.pattern = ParseDropPattern("drop_pattern", FLAGS_drop_pattern);
  options.gaps.blackouts = ParseBlackouts("blackouts", FLAGS_blackouts);
  options.faults.gyro_units = FLAGS_imu_gyro_units;
  options.faults.accel_units = FLAGS_imu_accel_units;
  options.faults.swap_cameras = FLAGS_swap_cameras;
  options.rig.time_offset_ms = FLAGS_time_offset_ms;
  options.rig.extrinsic_error_deg = FLAGS_extrinsic_error_deg;
  options.rig.extrinsic_error_m = FLAGS_extrinsic_error_m;
  if (!FLAGS_extrinsic_error_axis.empty()) {
    options.rig.rotation_axis = ParseVector3("extrinsic_error_axis", FLAGS_extrinsic_error_axis);
  }
  if (!FLAGS_extrinsic_error_direction.empty()) {
    options.rig.translation_direction = ParseVector3("extrinsic_error_direction", FLAGS_extrinsic_error_direction);
  }
  return options;
}

}  // namespace

int SimulateMain(const std::vector<std::string>& args) {
  if (!args.empty()) {
    std::cerr << "vio simulate: unexpected argument '" << args.front() << "' (see `vio simulate --help`)\n";
    return 2;
  }
  try {
    const SimulatorOptions options = OptionsFromFlags();
    if (options.output_dir.empty()) {
      std::cerr << "vio simulate: --output_dir is required (see `vio simulate --help`)\n";
      return 2;
    }
    std::optional<ProgressBar> bar;  // images mode only: one tick per written image
    const SimulationSummary summary = Simulate(options, [&bar](std::int64_t done, std::int64_t total) {
      if (!bar) bar.emplace(total, "images");
      bar->Update(done);
      if (done == total) bar->Finish();
    });
    std::cout << FormatSummary(summary, options.output_dir);
    return 0;
  } catch (const std::invalid_argument& e) {
    std::cerr << "vio simulate: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "vio simulate: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace vio::tools
