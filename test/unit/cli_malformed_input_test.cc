// Table of broken inputs and flags run through the real command line
// (VIO_BINARY) on a short synthetic dataset: each row mutates a copy of the
// dataset or writes a config, runs one `vio` command and asserts the exit
// code (a crash is never one of 0, 1, 2), a substring of the message, that a
// file already in the output folder is still there, and for runs that stop
// mid-way that what was estimated is written with a status that says so.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteFile(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// 6 s of synthetic flight (3 s static start, 20 Hz frames, 200 Hz IMU).
const std::string& CleanDataset() {
  static const std::string dir = [] {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("cli_malformed") + "/clean";
    options.duration_s = 6.0;
    options.seed = 5;
    Simulate(options);
    return options.output_dir;
  }();
  return dir;
}

// ---- mutations of a dataset copy ---------------------------------------------

using Rows = std::vector<std::string>;

// The data rows of a CSV (comments and header kept aside), edited, written back.
void EditCsv(const std::string& path, const std::function<void(Rows&)>& edit) {
  std::istringstream in(ReadFile(path));
  std::string header;
  Rows rows;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] == '#') {
      header += line + "\n";
    } else if (!line.empty()) {
      rows.push_back(line);
    }
  }
  edit(rows);
  std::string text = header;
  for (const std::string& row : rows) text += row + "\n";
  WriteFile(path, text);
}

std::int64_t Stamp(const std::string& row) { return std::stoll(row.substr(0, row.find(','))); }

std::string WithStamp(const std::string& row, std::int64_t t_ns) {
  return std::to_string(t_ns) + row.substr(row.find(','));
}

std::string Field(const std::string& row, int column) {
  std::stringstream ss(row);
  std::string field;
  for (int i = 0; i <= column; ++i) std::getline(ss, field, ',');
  return field;
}

std::string WithField(const std::string& row, int column, const std::string& value) {
  std::stringstream ss(row);
  std::vector<std::string> fields;
  for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
  fields[static_cast<size_t>(column)] = value;
  std::string out;
  for (size_t i = 0; i < fields.size(); ++i) out += (i ? "," : "") + fields[i];
  return out;
}

std::string Imu(const std::string& d) { return d + "/mav0/imu0/data.csv"; }
std::string Features(const std::string& d) { return d + "/mav0/features0/data.csv"; }
std::vector<std::string> EveryStampedFile(const std::string& d) {
  return {Imu(d), d + "/mav0/cam0/data.csv", d + "/mav0/cam1/data.csv", Features(d),
          d + "/mav0/state_groundtruth_estimate0/data.csv"};
}

constexpr std::int64_t kSecond = 1'000'000'000;

std::int64_t FirstImuStamp(const std::string& d) {
  std::int64_t first = 0;
  EditCsv(Imu(d), [&](Rows& rows) { first = Stamp(rows.front()); });
  return first;
}

// Removes the IMU rows in [from, from + length) seconds after the IMU start.
std::function<void(const std::string&)> ImuGap(double from_s, double length_s) {
  return [=](const std::string& d) {
    const std::int64_t t0 = FirstImuStamp(d) + static_cast<std::int64_t>(from_s * kSecond);
    const std::int64_t t1 = t0 + static_cast<std::int64_t>(length_s * kSecond);
    EditCsv(Imu(d), [&](Rows& rows) {
      Rows kept;
      for (const std::string& r : rows) {
        if (Stamp(r) < t0 || Stamp(r) >= t1) kept.push_back(r);
      }
      rows = kept;
    });
  };
}

// Every sensor's clock jumps by `jump_s` at `at_s` after the IMU start.
std::function<void(const std::string&)> TimeJump(double at_s, double jump_s) {
  return [=](const std::string& d) {
    const std::int64_t at = FirstImuStamp(d) + static_cast<std::int64_t>(at_s * kSecond);
    const auto jump = static_cast<std::int64_t>(jump_s * kSecond);
    for (const std::string& file : EveryStampedFile(d)) {
      EditCsv(file, [&](Rows& rows) {
        for (std::string& r : rows) {
          if (Stamp(r) >= at) r = WithStamp(r, Stamp(r) + jump);
        }
      });
    }
  };
}

// The IMU's stamps shifted by `offset_s` against every other sensor.
std::function<void(const std::string&)> ImuClockOffset(double offset_s) {
  return [=](const std::string& d) {
    EditCsv(Imu(d), [&](Rows& rows) {
      for (std::string& r : rows) r = WithStamp(r, Stamp(r) + static_cast<std::int64_t>(offset_s * kSecond));
    });
  };
}

// The IMU file ends `cut_s` before its end.
std::function<void(const std::string&)> ImuTruncated(double cut_s) {
  return [=](const std::string& d) {
    EditCsv(Imu(d), [&](Rows& rows) {
      const std::int64_t end = Stamp(rows.back()) - static_cast<std::int64_t>(cut_s * kSecond);
      while (Stamp(rows.back()) > end) rows.pop_back();
    });
  };
}

// IMU row `index` gets `value` in `column` (1-3 gyro, 4-6 accel).
std::function<void(const std::string&)> ImuValue(int index, int column, const std::string& value) {
  return [=](const std::string& d) {
    EditCsv(Imu(d), [&](Rows& rows) { rows[static_cast<size_t>(index)] = WithField(rows[index], column, value); });
  };
}

// One cam0 feature row late in the run gets u = `u_px`.
std::function<void(const std::string&)> FeatureU(const std::string& u_px) {
  return [=](const std::string& d) {
    EditCsv(Features(d), [&](Rows& rows) {
      const size_t i = rows.size() * 9 / 10;
      for (size_t k = i; k < rows.size(); ++k) {
        if (Field(rows[k], 1) == "0") {
          rows[k] = WithField(rows[k], 3, u_px);
          return;
        }
      }
    });
  };
}

// A feature seen in the previous frame, moved by `shift_px` in both cameras
// of a late frame (same disparity and row: only the gate can catch it).
std::function<void(const std::string&)> FeatureMovedInBothCameras(double shift_px) {
  return [=](const std::string& d) {
    EditCsv(Features(d), [&](Rows& rows) {
      std::map<std::int64_t, std::set<std::string>> ids_by_time;
      for (const std::string& r : rows) ids_by_time[Stamp(r)].insert(Field(r, 2));
      const auto frame = std::next(ids_by_time.begin(), static_cast<long>(ids_by_time.size() * 9 / 10));
      const std::set<std::string>& previous = std::prev(frame)->second;
      std::string id;
      for (const std::string& r : rows) {
        const double u = std::stod(Field(r, 3));
        if (Stamp(r) == frame->first && previous.count(Field(r, 2)) && u > 100 && u < 400) {
          id = Field(r, 2);
          break;
        }
      }
      ASSERT_FALSE(id.empty());
      for (std::string& r : rows) {
        if (Stamp(r) == frame->first && Field(r, 2) == id) {
          r = WithField(r, 3, std::to_string(std::stod(Field(r, 3)) + shift_px));
        }
      }
    });
  };
}

// ---- the table -------------------------------------------------------------------

struct MalformedRun {
  MalformedRun(std::string name_, std::function<void(const std::string&)> mutate_, std::string args_,
               std::string config_, int exit_code_, std::string message_, std::string summary_contains_ = "",
               bool trajectory_rows_ = false)
      : name(std::move(name_)), mutate(std::move(mutate_)), args(std::move(args_)), config(std::move(config_)),
        exit_code(exit_code_), message(std::move(message_)), summary_contains(std::move(summary_contains_)),
        trajectory_rows(trajectory_rows_) {}
  std::string name;
  std::function<void(const std::string&)> mutate;  ///< on a copy of the dataset; empty = none
  std::string args;                                ///< after `vio`; DATASET, OUT, CONFIG are replaced
  std::string config;                              ///< written to CONFIG when not empty
  int exit_code = 1;
  std::string message;           ///< substring of the output (stdout and stderr)
  std::string summary_contains;  ///< substring of OUT/summary.json; empty = no summary expected
  bool trajectory_rows = false;  ///< OUT/trajectory.txt must hold estimated rows
};

const std::string kRun = "run --dataset=DATASET --output_dir=OUT ";

std::vector<MalformedRun> Cases() {
  return {
      // IMU gaps and time jumps: the run stops at the gap, keeps what it estimated.
      {"imu gap 0.5 s", ImuGap(4.0, 0.5), kRun, "", 1, "(longer than model.max_imu_gap_s = 0.1 s)",
       "\"status\": \"imu_gap\"", true},
      {"imu gap 2 s", ImuGap(3.5, 2.0), kRun, "", 1, "IMU gap of 2", "\"status\": \"imu_gap\"", true},
      {"imu gap names the line", ImuGap(4.0, 0.5), kRun, "", 1, "mav0/imu0/data.csv:", "imu0/data.csv:", true},
      {"every sensor jumps +10 s", TimeJump(4.5, 10.0), kRun, "", 1, "IMU gap of 10", "\"status\": \"imu_gap\"",
       true},
      {"imu gap with msckf", ImuGap(4.0, 0.6), kRun + "--policy=msckf", "", 1, "IMU gap of 0.6",
       "\"frames_after_stop\": ", true},
      // Frames outside the IMU span: counted, reported, not ok.
      {"imu clock 1 s late", ImuClockOffset(1.0), kRun, "", 1, "before the first IMU sample",
       "\"frames_before_imu\": 20", true},
      {"imu clock 1 s early", ImuClockOffset(-1.0), kRun, "", 1, "after the last IMU sample",
       "\"frames_after_imu\": 20", true},
      {"imu file truncated", ImuTruncated(1.5), kRun, "", 1, "after the last IMU sample",
       "\"frames_after_imu\": ", true},
      {"groundtruth init before the imu", ImuGap(0.0, 0.5), kRun + "--init=groundtruth", "", 1,
       "before the first IMU sample", "\"status\": \"frames_skipped\"", true},
      // Impossible IMU values: an error naming file, line and column.
      {"imu accel 1e300", ImuValue(300, 4, "1e300"), kRun, "", 1, "imu0/data.csv:302: column 5", "", false},
      {"imu gyro 1e5", ImuValue(10, 2, "1e5"), kRun, "", 1, "beyond any IMU's gyro range", "", false},
      {"imu accel -1e7", ImuValue(20, 6, "-1e7"), kRun, "", 1, "beyond any IMU's accelerometer range", "",
       false},
      // Outlier observations: rejected before the cost, counted, the run is ok.
      {"observation at u = -50", FeatureU("-50"), kRun, "", 0, "status ok", "\"rejected_outside_image\": 1", true},
      {"observation at u = 5000", FeatureU("5000"), kRun, "", 0, "status ok", "\"rejected_outside_image\": 1",
       true},
      {"observation 150 px off", FeatureMovedInBothCameras(150), kRun, "", 0, "status ok",
       "\"rejected_observations\": 1", true},
      // A malformed features row is found when the run reaches it: the frames before it are written.
      {"features row malformed late", FeatureU("12x"), kRun, "", 1, "features0/data.csv:",
       "\"status\": \"failed\"", true},
      // Options out of range: named, with the valid range.
      {"window size 0", {}, kRun + "--window_size=0", "", 1, "--window_size: '0' is outside the valid range [1, inf)"},
      {"window size -1", {}, kRun + "--window_size=-1", "", 1, "--window_size: '-1' is outside the valid range"},
      {"msckf window 1", {}, kRun + "--policy=msckf --window_size=1", "", 1,
       "--window_size=1: the msckf policy needs a window of at least 2 states"},
      {"fixed_lag window 1", {}, kRun + "--policy=fixed_lag --window_size=1", "", 1,
       "the fixed_lag policy needs a window of at least 2"},
      {"max iterations 0", {}, kRun + "--max_iterations=0", "", 1, "--max_iterations: '0' is outside"},
      {"num threads 0", {}, kRun + "--num_threads=0", "", 1, "--num_threads: '0' is outside the valid range [1, 256]"},
      {"pixel sigma 0", {}, kRun + "--pixel_sigma=0", "", 1, "--pixel_sigma: '0' is outside the valid range (0, inf)"},
      {"pixel sigma nan", {}, kRun + "--pixel_sigma=nan", "", 1, "--pixel_sigma: expected a finite number"},
      {"unknown policy", {}, kRun + "--policy=kalman", "", 1, "--policy: 'kalman' is not one of swf|msckf"},
      {"int overflow in a flag", {}, kRun + "--window_size=99999999999", "", 1, "window_size"},
      {"keyframe overlap 1.5", {}, kRun + "--keyframe_overlap=1.5", "", 1, "valid range [0, 1]"},
      {"klt min ncc 2", {}, kRun + "--klt_min_ncc=2", "", 1, "--klt_min_ncc: '2' is outside"},
      {"negative solver time", {}, kRun + "--max_solver_time_s=-1", "", 1, "--max_solver_time_s: '-1' is outside"},
      {"negative huber", {}, kRun + "--huber_px=-1", "", 1, "--huber_px: '-1' is outside"},
      {"zero imu gap bound", {}, kRun + "--max_imu_gap_s=0", "", 1, "--max_imu_gap_s: '0' is outside"},
      // Config files: file, line and key.
      {"yaml value of the wrong kind", {}, kRun + "--config=CONFIG", "solver:\n  max_iterations: [1, 2]\n", 1,
       "cfg.yaml:2: 'max_iterations' must be a single value"},
      {"yaml section not a map", {}, kRun + "--config=CONFIG", "solver: 5\n", 1,
       "cfg.yaml:1: section 'solver' must be a map"},
      {"yaml duplicated section", {}, kRun + "--config=CONFIG",
       "solver:\n  max_iterations: 3\npolicy:\n  window_size: 5\nsolver:\n  max_iterations: 7\n", 1,
       "cfg.yaml:5: section 'solver' appears twice (first on line 1)"},
      {"yaml duplicated key", {}, kRun + "--config=CONFIG", "policy:\n  window_size: 5\n  window_size: 7\n", 1,
       "cfg.yaml:3: key 'window_size' appears twice (first on line 2)"},
      {"yaml key not a word", {}, kRun + "--config=CONFIG", "policy:\n  [a, b]: 5\n", 1,
       "cfg.yaml:2: key names must be plain words"},
      {"yaml value out of range", {}, kRun + "--config=CONFIG", "policy:\n  window_size: 0\n", 1,
       "cfg.yaml:2: 'window_size': '0' is outside the valid range [1, inf)"},
      {"yaml not a number", {}, kRun + "--config=CONFIG", "solver:\n  max_iterations: many\n", 1,
       "cfg.yaml:2: 'max_iterations': expected an integer, got 'many'"},
      {"yaml int overflow", {}, kRun + "--config=CONFIG", "solver:\n  max_iterations: 99999999999\n", 1,
       "cfg.yaml:2: 'max_iterations': expected an integer"},
      {"yaml nan", {}, kRun + "--config=CONFIG", "model:\n  pixel_sigma: .nan\n", 1,
       "cfg.yaml:2: 'pixel_sigma': expected a finite number"},
      {"yaml unknown key", {}, kRun + "--config=CONFIG", "model:\n  pixel_sigmaa: 1\n", 1,
       "cfg.yaml:2: unknown key 'pixel_sigmaa' in section 'model'"},
      {"yaml syntax error", {}, kRun + "--config=CONFIG", "model:\n  pixel_sigma: [1\n", 1, "cfg.yaml:3: "},
      {"yaml msckf window 1", {}, kRun + "--config=CONFIG", "policy:\n  policy: msckf\n  window_size: 1\n", 1,
       "the msckf policy needs a window of at least 2"},
      // Sweeps: run lists and jobs.
      {"sweep run without window", {}, "sweep --datasets=DATASET --output_dir=OUT --runs=swf: --plots=false", "",
       2, "--runs: 'swf:' is not policy:window"},
      {"sweep run without policy", {}, "sweep --datasets=DATASET --output_dir=OUT --runs=:5 --plots=false", "", 2,
       "--runs: ':5' is not policy:window"},
      {"sweep duplicated run", {},
       "sweep --datasets=DATASET --output_dir=OUT --runs=swf:5,swf:5 --jobs=2 --plots=false", "", 2,
       "run swf:5 is listed twice"},
      {"sweep window 0", {}, "sweep --datasets=DATASET --output_dir=OUT --window_sizes=0 --plots=false", "", 2,
       "window size 0 < 1"},
      {"sweep run window 0", {}, "sweep --datasets=DATASET --output_dir=OUT --runs=swf:0 --plots=false", "", 2,
       "window size 0 < 1"},
      {"sweep jobs 0", {}, "sweep --datasets=DATASET --output_dir=OUT --jobs=0 --plots=false", "", 2,
       "--jobs must be >= 1"},
      // vio eval.
      {"eval negative gap bound", {},
       "eval --estimate=DATASET/mav0/cam0/data.csv --groundtruth=DATASET --max_gt_gap_s=-1", "", 2,
       "--max_gt_gap_s: -1"},
      {"eval unknown alignment", {},
       "eval --estimate=DATASET/mav0/cam0/data.csv --groundtruth=DATASET --alignment=affine", "", 2, "affine"},
  };
}

struct Command {
  int exit_code = -1;  ///< -1: ended by a signal
  std::string output;
};

Command Shell(const std::string& command, const std::string& log) {
  const int status = std::system(("{ " + command + "; } > " + log + " 2>&1").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ReadFile(log)};
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  for (size_t pos = 0; (pos = text.find(from, pos)) != std::string::npos; pos += to.size()) {
    text.replace(pos, from.size(), to);
  }
  return text;
}

int DataRows(const std::string& text) {
  std::istringstream in(text);
  int rows = 0;
  for (std::string line; std::getline(in, line);) rows += !line.empty() && line[0] != '#';
  return rows;
}

class MalformedInput : public ::testing::TestWithParam<MalformedRun> {};

TEST_P(MalformedInput, ExitsWithAClearMessageAndKeepsWhatWasWritten) {
  const MalformedRun& c = GetParam();
  const std::string dir = test::MakeTempDir("cli_malformed_case");
  std::string dataset = CleanDataset();
  if (c.mutate) {
    dataset = dir + "/dataset";
    fs::copy(CleanDataset(), dataset, fs::copy_options::recursive);
    c.mutate(dataset);
  }
  const std::string out = dir + "/out";
  WriteFile(out + "/previous_result.txt", "kept");
  const std::string config = dir + "/cfg.yaml";
  if (!c.config.empty()) WriteFile(config, c.config);
  std::string args = Replace(Replace(Replace(c.args, "DATASET", dataset), "OUT", out), "CONFIG", config);
  const Command run = Shell(std::string(VIO_BINARY) + " " + args + " --minloglevel=1", dir + "/log.txt");
  EXPECT_EQ(run.exit_code, c.exit_code) << run.output;
  EXPECT_THAT(run.output, HasSubstr(c.message));
  EXPECT_EQ(ReadFile(out + "/previous_result.txt"), "kept") << "a file already in the output folder was lost";
  if (!c.summary_contains.empty()) {
    EXPECT_THAT(ReadFile(out + "/summary.json"), HasSubstr(c.summary_contains));
  }
  if (c.trajectory_rows) {
    EXPECT_GE(DataRows(ReadFile(out + "/trajectory.txt")), 10) << "nothing estimated kept";
  }
}

TEST(MalformedInputTable, CoversAtLeastFortyCases) { EXPECT_GE(Cases().size(), 40u); }

std::string CaseName(const ::testing::TestParamInfo<MalformedRun>& info) {
  std::string name;
  for (const char ch : info.param.name) name += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Table, MalformedInput, ::testing::ValuesIn(Cases()), CaseName);

}  // namespace
}  // namespace vio::tools
