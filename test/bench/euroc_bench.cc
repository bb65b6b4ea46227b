// Reading a whole sequence's IMU file (V2_01_easy, 22,800 rows) with the
// EuRoC reader; skipped when the real data ($VIO_DATA_DIR, else
// ../shared/data next to the source tree) is absent.
//   build/bin/vio_bench --benchmark_filter=ReadImuCsv
#include <cstdlib>
#include <filesystem>
#include <string>

#include <benchmark/benchmark.h>

#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

std::string DataDir() {
  const char* env = std::getenv("VIO_DATA_DIR");
  return env != nullptr && *env ? env : VIO_BENCH_DATA_DIR;
}

void BM_ReadImuCsv(benchmark::State& state) {
  const std::string path = DataDir() + "/euroc/V2_01_easy/mav0/imu0/data.csv";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("no real data at " + path).c_str());
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(ReadImuCsv(path));
}
BENCHMARK(BM_ReadImuCsv)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vio::tools
