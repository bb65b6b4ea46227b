#include "run_control.h"

#include <csignal>
#include <cstdio>

#include <glog/logging.h>

namespace vio::tools {

std::string SignalName(int signal) {
  if (signal == SIGINT) return "SIGINT";
  if (signal == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal);
}

void SolveProgressLog::SetPhase(std::string phase) { phase_ = std::move(phase); }

void SolveProgressLog::Hear(const SolveProgress& progress) {
  last_ = progress;
  if (progress.elapsed_s < kLongSolveS) {
    if (noted_ && bar_ != nullptr) bar_->SetNote("");
    noted_ = false;
    return;
  }
  char text[160];
  std::snprintf(text, sizeof(text), "%s: iteration %d/%d, cost %.6g (from %.6g), %.1f s", phase_.c_str(),
                progress.iteration, progress.max_iterations, progress.cost, progress.initial_cost,
                progress.elapsed_s);
  if (bar_ != nullptr) bar_->ClearLine();
  LOG(INFO) << text;
  if (bar_ != nullptr) bar_->SetNote(text);
  noted_ = true;
}

SolveControl MakeSolveControl(const RunRequest& request, SolveProgressLog* log) {
  SolveControl control;
  control.stop = [&request] { return StopSignalOf(request) != 0; };
  control.progress = [log](const SolveProgress& progress) { log->Hear(progress); };
  return control;
}

}  // namespace vio::tools
