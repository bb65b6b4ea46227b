#include "run_output.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "json_writer.h"
#include "vio/estimator/pose_manifold.h"

namespace vio::tools {
namespace {

std::ofstream OpenForWriting(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  return out;
}

// Mean over frames of one stage time.
template <class Get>
double MeanMs(const std::vector<FrameEstimate>& frames, Get get) {
  if (frames.empty()) return 0.0;
  double sum = 0;
  for (const FrameEstimate& f : frames) sum += get(f);
  return sum / static_cast<double>(frames.size());
}

// `temp` (written in full) becomes `path`: a reader, or a run killed while
// writing, sees the old file or the new one, never a part.
void RenameOver(const std::string& temp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) throw std::runtime_error(path + ": cannot replace: " + ec.message());
}

std::string StageTimesJson(const std::vector<FrameEstimate>& f) {
  std::ostringstream os;
  os << "{\"propagate\": " << JsonNumber(MeanMs(f, [](auto& e) { return e.timing.propagate_ms; }))
     << ", \"build\": " << JsonNumber(MeanMs(f, [](auto& e) { return e.timing.policy.build_ms; }))
     << ", \"solve\": " << JsonNumber(MeanMs(f, [](auto& e) { return e.timing.policy.solve_ms; }))
     << ", \"marginalize\": " << JsonNumber(MeanMs(f, [](auto& e) { return e.timing.policy.marginalize_ms; }))
     << ", \"total\": " << JsonNumber(MeanMs(f, [](auto& e) { return e.timing.total_ms; })) << "}";
  return os.str();
}

std::string RefinementJson(const RefinementReport& r) {
  std::ostringstream out;
  out << "{\"seconds\": " << JsonNumber(r.seconds) << ", \"iterations\": " << r.iterations
      << ", \"states\": " << r.states << ", \"landmarks\": " << r.landmarks
      << ", \"dropped_observations\": " << r.dropped_observations
      << ", \"started_landmarks\": " << r.started_landmarks
      << ", \"triangulated_landmarks\": " << r.triangulated_landmarks
      << ", \"initial_cost\": " << JsonNumber(r.initial_cost) << ", \"final_cost\": " << JsonNumber(r.final_cost)
      << ", \"usable\": " << (r.usable ? "true" : "false") << "}";
  return out.str();
}

std::string HealthJson(const RunHealth& h) {
  std::ostringstream os;
  os << "{\"frames_waiting_init\": " << h.frames_waiting_init << ", \"frames_before_imu\": " << h.frames_before_imu << ", \"frames_after_imu\": " << h.frames_after_imu
     << ", \"frames_after_stop\": " << h.frames_after_stop
     << ", \"rejected_observations\": " << h.rejected_observations
     << ", \"dropped_residuals\": " << h.dropped_residuals << ", \"failed_solves\": " << h.failed_solves
     << ", \"rejected_steps\": " << h.rejected_steps << ", \"dropped_observations\": " << h.dropped_observations
     << "}";
  return os.str();
}

std::string ProblemsJson(const std::vector<std::string>& problems) {
  std::string out = "[";
  for (const std::string& p : problems) out += (out.size() > 1 ? ", " : "") + JsonString(p);
  return out + "]";
}

}  // namespace

RunOutput::RunOutput(std::string dir) : dir_(std::move(dir)) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw std::runtime_error(dir_ + ": cannot create output folder: " + ec.message());
}

void RunOutput::AddFrame(const FrameEstimate& estimate) {
  GroundTruthState pose;
  pose.t_ns = estimate.t_ns;
  pose.p_w_b = estimate.p_w_b;
  pose.q_w_b = estimate.q_w_b;
  pose.v_w_b = estimate.v_w_b;
  pose.gyro_bias = estimate.gyro_bias;
  pose.accel_bias = estimate.accel_bias;
  trajectory_.push_back(pose);
  frames_.push_back(estimate);
  const std::string path = dir_ + "/trajectory.txt";
  if (!streamed_.is_open()) {
    streamed_.open(path, std::ios::binary | std::ios::trunc);
    streamed_ << kTumTrajectoryHeader;
  }
  streamed_ << TumTrajectoryLine(pose, path) << std::flush;
  if (!streamed_) throw std::runtime_error(path + ": cannot write");
}

void RunOutput::ReplaceEstimates(const std::vector<FrameEstimate>& estimates) {
  std::map<Timestamp, const FrameEstimate*> by_time;
  for (const FrameEstimate& e : estimates) by_time[e.t_ns] = &e;
  for (GroundTruthState& pose : trajectory_) {
    auto it = by_time.find(pose.t_ns);
    if (it == by_time.end()) continue;
    pose.p_w_b = it->second->p_w_b;
    pose.q_w_b = it->second->q_w_b;
    pose.v_w_b = it->second->v_w_b;
    pose.gyro_bias = it->second->gyro_bias;
    pose.accel_bias = it->second->accel_bias;
  }
}

void RunOutput::WriteTrajectory() {
  if (streamed_.is_open()) streamed_.close();
  const std::string path = dir_ + "/trajectory.txt";
  WriteTumTrajectory(trajectory_, path + ".tmp");
  RenameOver(path + ".tmp", path);
}

void RunOutput::WriteTiming(const RefinementReport& refinement) const {
  std::ofstream out = OpenForWriting(dir_ + "/timing.csv");
  out << "#timestamp [ns],propagate [ms],build [ms],solve [ms],marginalize [ms],total [ms],"
         "solver_iterations,states,landmarks,observations,residual blocks\n";
  for (const FrameEstimate& f : frames_) {
    const PolicyTiming& p = f.timing.policy;
    out << f.t_ns << "," << JsonNumber(f.timing.propagate_ms) << "," << JsonNumber(p.build_ms) << ","
        << JsonNumber(p.solve_ms) << "," << JsonNumber(p.marginalize_ms) << "," << JsonNumber(f.timing.total_ms) << ","
        << p.solver_iterations << "," << f.num_states << "," << f.num_landmarks << "," << f.num_observations
        << "," << f.num_residuals << "\n";
  }
  if (refinement.ran) {
    out << "# refinement [ms],solver_iterations,states,landmarks: " << JsonNumber(1e3 * refinement.seconds) << ","
        << refinement.iterations << "," << refinement.states << "," << refinement.landmarks << "\n";
  }
}

namespace {

// summary.json's calibration.extrinsics_*: the correction's rotation and translation (norms and vectors).
void WriteExtrinsics(const CalibrationReport& c, std::ostream& out) {
  const auto vector = [](const Eigen::Vector3d& v) {
    return "[" + JsonNumber(v.x()) + ", " + JsonNumber(v.y()) + ", " + JsonNumber(v.z()) + "]";
  };
  out << ", \"extrinsics_estimated\": " << (c.extrinsics_estimated ? "true" : "false")
      << ", \"extrinsics_rotation_deg\": " << JsonNumber(c.extrinsics_rotation_deg.norm())
      << ", \"extrinsics_translation_m\": " << JsonNumber(c.extrinsics_translation_m.norm())
      << ", \"extrinsics_rotation_vector_deg\": " << vector(c.extrinsics_rotation_deg)
      << ", \"extrinsics_translation_vector_m\": " << vector(c.extrinsics_translation_m);
  if (c.extrinsics_rotation_sigma_deg) out << ", \"extrinsics_rotation_sigma_deg\": " << JsonNumber(*c.extrinsics_rotation_sigma_deg);
  if (c.extrinsics_translation_sigma_m) out << ", \"extrinsics_translation_sigma_m\": " << JsonNumber(*c.extrinsics_translation_sigma_m);
  if (c.rig_rotation_search_deg) {
    out << ", \"rig_rotation_search\": {\"rotation_vector_deg\": " << vector(*c.rig_rotation_search_deg)
        << ", \"rotation_deg\": " << JsonNumber(c.rig_rotation_search_deg->norm())
        << ", \"sigma_deg\": " << JsonNumber(c.rig_rotation_search_sigma_deg)
        << ", \"excited\": " << (c.rig_rotation_search_excited ? "true" : "false")
        << ", \"restarted\": " << (c.rig_rotation_search_restarted ? "true" : "false") << "}";
  }
  if (c.extrinsics_probe) {
    const CalibrationReport::ExtrinsicsProbe& p = *c.extrinsics_probe;
    out << ", \"extrinsics_probe\": {\"duration_s\": " << JsonNumber(p.duration_s)
        << ", \"rotation_deg\": " << JsonNumber(p.rotation_deg.norm())
        << ", \"translation_m\": " << JsonNumber(p.translation_m.norm())
        << ", \"rotation_vector_deg\": " << vector(p.rotation_deg) << ", \"translation_vector_m\": " << vector(p.translation_m);
    if (p.rotation_sigma_deg) out << ", \"rotation_sigma_deg\": " << JsonNumber(*p.rotation_sigma_deg);
    if (p.translation_sigma_m) out << ", \"translation_sigma_m\": " << JsonNumber(*p.translation_sigma_m);
    if (p.chi2) out << ", \"chi2\": " << JsonNumber(*p.chi2);
    out << ", \"applied\": " << (p.applied ? "true" : "false") << "}";
  }
}

}  // namespace

void RunOutput::WriteSummary(const RunResult& r, const std::string& frontend_json, const RunRequest& request,
                             double peak_memory_mb, const std::string& waiting_reason) const {
  std::ofstream out = OpenForWriting(dir_ + "/summary.json.tmp");
  const PolicyOptions& policy = request.config.estimator.policy;
  out << "{\n  \"dataset\": " << JsonString(request.dataset_dir) << ",\n  \"policy\": " << JsonString(policy.policy)
      << ",\n  \"window_size\": " << policy.window_size
      << ",\n  \"trajectory\": " << JsonString(r.trajectory)
      << ",\n  \"status\": " << JsonString(r.status)
      << ",\n  \"problems\": " << ProblemsJson(r.problems) << ",\n  \"health\": " << HealthJson(r.health)
      << ",\n  \"frames\": " << r.frames << ",\n  \"frames_estimated\": " << r.frames_estimated
      << ",\n  \"dataset_duration_s\": " << JsonNumber(r.dataset_duration_s)
      << ",\n  \"processing_s\": " << JsonNumber(r.processing_s) << ",\n  \"ms_per_frame\": " << JsonNumber(r.ms_per_frame)
      << ",\n  \"real_time_factor\": " << JsonNumber(r.real_time_factor)
      << ",\n  \"stage_ms_per_frame\": " << StageTimesJson(frames_)
      << ",\n  \"peak_memory_mb\": " << JsonNumber(peak_memory_mb) << ",\n  \"frame_gaps\": {\"count\": " << r.frame_gaps
      << ", \"longest_s\": " << JsonNumber(r.longest_frame_gap_s) << "},\n  \"tracking_loss\": {\"untracked_frames\": "
      << r.tracking.untracked_frames << ", \"losses\": " << r.tracking.losses << ", \"losses_beyond_window\": "
      << r.tracking.losses_beyond_window << ", \"longest_s\": " << JsonNumber(r.tracking.longest_loss_s)
      << "},\n  \"frontend\": " << frontend_json;
  if (!waiting_reason.empty()) out << ",\n  \"not_initialized_reason\": " << JsonString(waiting_reason);
  out << ",\n  \"init\": {\"method\": " << JsonString(r.init.method) << ", \"wait_s\": " << JsonNumber(r.init.wait_s)
      << ", \"wait_frames\": " << r.init.wait_frames << ", \"last_reason\": " << JsonString(r.init.last_reason) << "}";
  out << ",\n  \"calibration\": {\"time_offset_estimated\": " << (r.calibration.time_offset_estimated ? "true" : "false")
      << ", \"time_offset_ms\": " << JsonNumber(r.calibration.time_offset_ms)
      << ", \"time_offset_calibration_ms\": " << JsonNumber(r.calibration.time_offset_calibration_ms);
  if (r.calibration.time_offset_sigma_ms) out << ", \"time_offset_sigma_ms\": " << JsonNumber(*r.calibration.time_offset_sigma_ms);
  if (r.calibration.time_offset_search_ms) {
    out << ", \"time_offset_search\": {\"offset_ms\": " << JsonNumber(*r.calibration.time_offset_search_ms)
        << ", \"sigma_ms\": " << JsonNumber(*r.calibration.time_offset_search_sigma_ms)
        << ", \"restarted\": " << (r.calibration.time_offset_search_restarted ? "true" : "false") << "}";
  }
  WriteExtrinsics(r.calibration, out);
  out << "}";
  if (r.groundtruth_tilt_deg) out << ",\n  \"groundtruth_tilt_deg\": " << JsonNumber(*r.groundtruth_tilt_deg);
  if (r.evaluation) {
    std::string evaluation = ToJson(*r.evaluation);
    for (size_t pos = 0; (pos = evaluation.find('\n', pos)) != std::string::npos; pos += 3) {
      evaluation.replace(pos, 1, "\n  ");
    }
    out << ",\n  \"evaluation\": " << evaluation;
  }
  if (r.nees) out << ",\n  \"nees\": " << NeesJson(*r.nees);
  if (r.refinement.ran) out << ",\n  \"refinement\": " << RefinementJson(r.refinement);
  out << "\n}\n";
  out.close();
  if (!out) throw std::runtime_error(dir_ + "/summary.json.tmp: cannot write");
  RenameOver(dir_ + "/summary.json.tmp", dir_ + "/summary.json");
}

void RunOutput::AddCovariance(const StateCovariance& covariance) { covariances_.push_back(covariance); }

void RunOutput::WriteCovariance() const {
  std::ofstream out = OpenForWriting(dir_ + "/covariance.csv");
  out << "#t_ns";
  for (int r = 0; r < kPoseTangentSize; ++r) {
    for (int c = r; c < kPoseTangentSize; ++c) out << ",pose_" << r << "_" << c;
  }
  out << ",var_vx,var_vy,var_vz,var_bgx,var_bgy,var_bgz,var_bax,var_bay,var_baz\n";
  out << std::setprecision(10);
  for (const StateCovariance& s : covariances_) {
    out << s.t_ns;
    for (int r = 0; r < kPoseTangentSize; ++r) {
      for (int c = r; c < kPoseTangentSize; ++c) out << "," << s.covariance(r, c);
    }
    for (int k = kPoseTangentSize; k < kStateTangentSize; ++k) out << "," << s.covariance(k, k);
    out << "\n";
  }
}

std::vector<PoseCovariance> RunOutput::PoseCovariances() const {
  std::vector<PoseCovariance> poses;
  for (const StateCovariance& s : covariances_) {
    poses.push_back({s.t_ns, s.covariance.topLeftCorner<kPoseTangentSize, kPoseTangentSize>()});
  }
  return poses;
}

void RunOutput::WriteNees(const NeesResult& nees) const { WriteNeesCsv(nees, dir_ + "/nees.csv"); }

void RunOutput::WriteConfig(const std::string& yaml) const { OpenForWriting(dir_ + "/config.yaml") << yaml; }

}  // namespace vio::tools
