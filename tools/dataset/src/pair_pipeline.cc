#include "pair_pipeline.h"

#include <sched.h>

#include <algorithm>
#include <utility>

#include <glog/logging.h>

namespace vio::tools {

int AvailableCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

PairPipeline::PairPipeline(size_t size, int threads, MakePair make)
    : size_(size), threads_(threads), make_(std::move(make)) {
  CHECK(threads == 1 || threads == 2) << "PairPipeline: threads must be 1 or 2";
  // The reader's queue, the pair it makes and the one being processed.
  for (size_t i = 0; i < kQueuedPairs + 2; ++i) free_.push_back(std::make_unique<frontend::PreparedPair>());
}

PairPipeline::~PairPipeline() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (reader_.joinable()) reader_.join();
}

std::unique_ptr<frontend::PreparedPair> PairPipeline::FreePair() {
  std::unique_ptr<frontend::PreparedPair> pair = std::move(free_.back());
  free_.pop_back();
  return pair;
}

// Pairs first, first + 1, ... into the queue while it has room.
void PairPipeline::Read(size_t first) {
  for (size_t k = first; k < size_; ++k) {
    PipelinePair slot;
    slot.k = k;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return stop_ || (queue_.size() < kQueuedPairs && !free_.empty()); });
      if (stop_) return;
      slot.pair = FreePair();
    }
    try {
      make_(&slot);
    } catch (...) {
      slot.error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back(std::move(slot));
    }
    changed_.notify_all();
  }
}

PipelinePair PairPipeline::Take(size_t k) {
  if (threads_ == 1) {
    PipelinePair slot;
    slot.k = k;
    slot.pair = FreePair();
    try {
      make_(&slot);
    } catch (...) {
      Give(std::move(slot));
      throw;
    }
    return slot;
  }
  if (!reader_.joinable()) reader_ = std::thread([this, k] { Read(k); });
  while (true) {
    PipelinePair slot;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return !queue_.empty(); });
      slot = std::move(queue_.front());
      queue_.pop_front();
    }
    changed_.notify_all();
    CHECK_LE(slot.k, k) << "PairPipeline: pairs must be taken in increasing order";
    if (slot.k == k && slot.error) {
      const std::exception_ptr error = slot.error;
      Give(std::move(slot));
      std::rethrow_exception(error);
    }
    if (slot.k == k) return slot;
    Give(std::move(slot));
  }
}

void PairPipeline::Give(PipelinePair done) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(done.pair));
  }
  changed_.notify_all();
}

}  // namespace vio::tools
