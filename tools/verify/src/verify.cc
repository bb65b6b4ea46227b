// `vio verify`: every equivalence check on random problems, as a table.
#include "vio/verify/verify.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "window_cases.h"
#include "window_checks.h"

namespace vio::tools {
namespace {

using marginalization::Deviation;

/// Theorem rows must move the mean: a whitened innovation of at least this.
constexpr double kMinInnovation = 1e-3;

void RequireValid(const VerifyOptions& options) {
  const bool sizes_ok = options.num_landmarks >= 1 && options.num_landmarks <= 50 && options.num_poses >= 2 &&
                        options.num_poses <= 20;
  if (!sizes_ok || options.trials < 1 || !(options.tolerance > 0.0)) {
    throw std::invalid_argument(std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                ": need num_landmarks in [1, 50], num_poses in [2, 20], trials >= 1 and "
                                "tolerance > 0");
  }
}

/// The smaller of two deviations, field-wise; NaN wins.
Deviation Min(const Deviation& a, const Deviation& b) {
  auto min = [](double x, double y) {
    return std::isnan(x) || std::isnan(y) ? std::numeric_limits<double>::quiet_NaN() : std::min(x, y);
  };
  return {min(a.mean, b.mean), min(a.covariance, b.covariance)};
}

/// Folds one trial's checks into the rows: the largest deviation of a
/// theorem, the smallest of a control (every trial's control must differ).
void Accumulate(const std::vector<WindowCheck>& checks, const std::string& kind, bool control,
                std::vector<VerifyRow>* rows) {
  for (const WindowCheck& check : checks) {
    auto row = std::find_if(rows->begin(), rows->end(), [&](const VerifyRow& r) {
      return r.kind == kind && r.control == control && r.description == check.description;
    });
    if (row == rows->end()) {
      rows->push_back({check.theorem, check.description, kind, control, check.deviation, check.innovation,
                       check.path, false});
      continue;
    }
    row->deviation = control ? Min(row->deviation, check.deviation)
                             : marginalization::Max(row->deviation, check.deviation);
    row->innovation = std::min(row->innovation, check.innovation);
    if (row->path != check.path) row->path = "mixed";
  }
}

bool RowPasses(const VerifyRow& row, double tolerance) {
  const bool within = row.deviation.mean <= tolerance && row.deviation.covariance <= tolerance &&
                      row.innovation >= kMinInnovation && row.path == "window";
  const bool beyond = row.deviation.mean > tolerance || row.deviation.covariance > tolerance;
  return row.control ? beyond : within;  // NaN passes neither
}

std::string Scientific(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1e", value);
  return text;
}

void AppendRow(const VerifyRow& row, std::ostringstream* out) {
  char line[128];
  std::snprintf(line, sizeof(line), "%-8s %-10s %-9s %-9s %-9s %-7s %-5s ", row.theorem.c_str(), row.kind.c_str(),
                Scientific(row.deviation.mean).c_str(), Scientific(row.deviation.covariance).c_str(),
                Scientific(row.innovation).c_str(), row.path.c_str(), row.passed ? "ok" : "FAIL");
  *out << line << row.description << "\n";
}

}  // namespace

VerifyReport RunVerification(const VerifyOptions& options) {
  RequireValid(options);
  VerifyReport report;
  report.options = options;
  for (const std::string kind : {"linear", "nonlinear"}) {
    for (int trial = 0; trial < options.trials; ++trial) {
      const window_cases::CaseSet cases = window_cases::RandomCases(
          kind, options.num_landmarks, options.num_poses, options.seed + static_cast<unsigned>(trial));
      Accumulate(CheckThroughWindow(cases), kind, /*control=*/false, &report.rows);
      Accumulate(ControlsThroughWindow(cases), kind, /*control=*/true, &report.rows);
    }
  }
  std::stable_sort(report.rows.begin(), report.rows.end(), [](const VerifyRow& a, const VerifyRow& b) {
    return a.control != b.control ? !a.control : a.theorem < b.theorem;
  });
  report.passed = true;
  for (VerifyRow& row : report.rows) {
    row.passed = RowPasses(row, options.tolerance);
    report.passed = report.passed && row.passed;
  }
  return report;
}

std::string FormatVerifyReport(const VerifyReport& report) {
  const VerifyOptions& o = report.options;
  std::ostringstream out;
  out << "equivalence theorems (design paper 4.3): " << o.trials << " random problems per kind, seeds "
      << o.seed << ".." << o.seed + static_cast<unsigned>(o.trials) - 1 << ", " << o.num_landmarks
      << " landmarks, " << o.num_poses << " poses\n"
      << "deviation = relative difference of the window's step and the Kalman form: mean, covariance; "
         "tolerance "
      << Scientific(o.tolerance) << "\ninnovation = smallest |whitened residual| of the step's factors at the "
         "linearization point (theorems need >= "
      << Scientific(kMinInnovation) << "); path = where the optimization side ran\n\n"
      << "theorem  kind       mean dev  cov dev   innov     path    result statement\n";
  bool controls_started = false;
  for (const VerifyRow& row : report.rows) {
    if (row.control && !controls_started) {
      out << "\nnegative controls (optimization side or filter side broken; must exceed the tolerance; smallest "
             "deviation shown):\n";
      controls_started = true;
    }
    AppendRow(row, &out);
  }
  out << "\n"
      << (report.passed ? "PASS" : "FAIL") << ": "
      << (report.passed ? "every theorem holds within the tolerance and every control is detected"
                        : "see the FAIL rows")
      << "\n";
  return out.str();
}

}  // namespace vio::tools
