// The stress suite's summary per area (render, fit, capture, probe, export): cases run,
// finite %, converged % (where the area has a notion of convergence), and outcomes by kind.
// A clear skycal::Error on hostile input is a pass; a non-finite output or any other
// exception (a crash kills the whole run, which CI sees as a failure) is not.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/bench/case_result.h"

namespace skycal::bench {

struct StressArea {
  std::string area;
  int cases = 0, ok = 0, clear_error = 0, non_finite = 0, crash = 0;
  int with_convergence = 0, converged = 0;
  double FinitePercent() const { return cases ? 100.0 * (cases - non_finite - crash) / cases : 100.0; }
  bool Passed() const { return non_finite == 0 && crash == 0; }
};

// Groups `cases` of suite "stress" by their "area" setting, in first-seen order.
std::vector<StressArea> StressTable(const std::vector<CaseResult>& cases);
nlohmann::json StressTableToJson(const std::vector<StressArea>& table);
std::string StressTableToText(const std::vector<StressArea>& table);  // a Markdown table

}  // namespace skycal::bench
