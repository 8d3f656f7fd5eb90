// `skycal bench --compare OLD.json NEW.json`: per case (matched by suite and case name) the
// time ratio new/old and whether it lies beyond the measured noise. Each case's noise is
// its relative spread, (max - min) / median, the larger of the two runs', never below
// CompareOptions::noise_floor: one-run cases have no spread, and these machines are shared.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/bench/results.h"

namespace skycal::bench {

struct CompareOptions {
  double noise_floor = 0.10;  // relative; a ratio within 1 +- max(noise, floor) is noise
  double error_tolerance = 0.05;  // relative growth of a case's error that counts as worse
  bool IsValid(std::string* why) const;
};

enum class Verdict { kSame, kSlower, kFaster, kOnlyOld, kOnlyNew };
const char* ToString(Verdict v);

struct CaseComparison {
  std::string suite, name;
  double old_ms = 0.0, new_ms = 0.0;
  double ratio = 0.0;   // new / old median
  double noise = 0.0;   // relative, as used for the verdict
  Verdict verdict = Verdict::kSame;
  double old_error = 0.0, new_error = 0.0;  // NaN where a run had none
  bool error_worse = false;
  std::string old_outcome, new_outcome;
};

struct Comparison {
  std::string old_commit, new_commit;
  std::vector<CaseComparison> cases;
  int slower = 0, faster = 0, error_worse = 0, outcome_worse = 0;
  bool Regressed() const { return slower + error_worse + outcome_worse > 0; }
  std::string ToText() const;
  nlohmann::json ToJson() const;
};

Comparison Compare(const Results& old_run, const Results& new_run, const CompareOptions& options);

}  // namespace skycal::bench
