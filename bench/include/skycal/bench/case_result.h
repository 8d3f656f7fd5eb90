// One measured case of a suite: its settings, time, error and outcome.
#pragma once
#include <limits>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/bench/grid.h"
#include "skycal/bench/timing.h"

namespace skycal::bench {

// How a case ended. A clear skycal::Error on hostile input is a pass for the stress
// suite (the tool refused and said why); a non-finite output or another exception is not.
enum class Outcome { kOk, kClearError, kNonFinite, kCrash };
const char* ToString(Outcome o);
Outcome ParseOutcome(const std::string& s);  // throws skycal::Error on an unknown name

struct CaseResult {
  std::string suite;
  std::string name;         // Label(settings), unique within the suite
  Settings settings;
  bool is_default = false;  // the settings a user gets without options
  Timing time;              // ms
  bool timed = true;        // false: the time is recorded, not benchmarked (one run of a stress case)
  double error = std::numeric_limits<double>::quiet_NaN();  // in the suite's error metric
  Outcome outcome = Outcome::kOk;
  std::string message;      // the error's text, or what was non-finite
  std::optional<bool> converged;  // where the case has a notion of convergence (fits)
  nlohmann::json extra = nlohmann::json::object();  // suite-specific numbers (counts, stages)
};

}  // namespace skycal::bench
