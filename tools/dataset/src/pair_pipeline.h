#pragma once
// The first stage of an image run's pipeline: stereo pairs read, decoded and
// prepared (StereoFrontend::Prepare: the work that needs no estimator state)
// in order, on a thread of their own with a bounded queue, or on the
// caller's thread. The second stage (tracking, which needs the estimator's
// prediction, then the estimator) takes them in order, so what it computes
// does not depend on the number of threads.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "vio/frontend/stereo_frontend.h"

namespace vio::tools {

/// One pair of the pipeline and what making it cost.
struct PipelinePair {
  size_t k = 0;
  std::unique_ptr<frontend::PreparedPair> pair;
  double decode_cpu_ms = 0;   ///< reading and decoding, CPU time of its thread
  double prepare_cpu_ms = 0;  ///< Prepare, CPU time of its thread
  double prepare_wall_ms = 0;
  std::exception_ptr error;   ///< what reading or preparing threw
};

/// The processors this process may run on (its CPU affinity), at least 1.
int AvailableCpus();

class PairPipeline {
 public:
  /// Fills pair `slot->k` into slot->pair (reusing its buffers) and the
  /// costs; may throw (the error then reaches Take).
  using MakePair = std::function<void(PipelinePair* slot)>;

  /// `threads` 1: Take makes the pair itself; 2: a reader thread makes pairs
  /// ahead, at most kQueuedPairs waiting.
  PairPipeline(size_t size, int threads, MakePair make);
  ~PairPipeline();
  PairPipeline(const PairPipeline&) = delete;
  PairPipeline& operator=(const PairPipeline&) = delete;

  /// Pair k (k above the last one taken; pairs in between are dropped);
  /// rethrows what making it threw. Give it back when done with it.
  PipelinePair Take(size_t k);
  void Give(PipelinePair done);

 private:
  static constexpr size_t kQueuedPairs = 2;

  void Read(size_t first);
  std::unique_ptr<frontend::PreparedPair> FreePair();

  const size_t size_;
  const int threads_;
  MakePair make_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<PipelinePair> queue_;
  std::vector<std::unique_ptr<frontend::PreparedPair>> free_;
  bool stop_ = false;
  std::thread reader_;  ///< started at the first Take (threads 2)
};

}  // namespace vio::tools
