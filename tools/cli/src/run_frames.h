#pragma once
// `vio run`'s frame loop (run.cc's passes run it): the IMU fed up to each frame, the front end, the
// estimator and the output, with the bad data and stop requests that end a pass early. Private to tools.
#include "run_output.h"
#include "run_probe.h"
#include "vio/cli/progress.h"
#include "vio/cli/run.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/frame_source.h"
#include "vio/dataset/observations_csv.h"
#include "vio/estimator/estimator.h"

namespace vio::tools {

/// The frame loop: IMU, (ground-truth start), front end, estimator, output.
/// Bad data mid-run ends the loop with a status; what was estimated is kept.
/// `observations` (null: none written) receives every frame the estimator is given.
/// A stop request ends it before the next frame, or (a solve cut short) drops the frame in hand.
/// `probe` (null: none in this pass), while it runs, is given each frame after the estimator.
/// Returns true when a search at initialization (time offset, rig rotation) found the rig beyond its
/// prior or the probe applied a correction (the pass ends there).
bool EstimateFrames(const RunRequest& request, const EurocDataset& dataset, FrameSource& source,
                    Estimator& estimator, RunOutput& output, ObservationsCsvWriter* observations,
                    ExtrinsicsProbe* probe, ProgressBar& progress, RunResult* result);

/// Frame intervals longer than 1.5 median intervals: missing frames.
void CountFrameGaps(const FrameSource& source, RunResult* result);

/// Frames outside the IMU's span cannot be estimated: counted, and an error when they reach further
/// than the IMU gap the estimate bridges (a clock offset between camera and IMU, or a truncated IMU file).
void ReportFramesOutsideImu(const EurocDataset& dataset, const FrameSource& source, double max_gap_s,
                            RunResult* result);

}  // namespace vio::tools
