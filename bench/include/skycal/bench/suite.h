// A benchmark suite and the registry `skycal bench --suite` picks from. A suite measures
// a grid of settings (grid.h) and returns one CaseResult per point; the verb writes them,
// computes the Pareto front and plots it. New areas (e.g. the clouds renderer and fit)
// register one more Suite in BuiltinSuites (suites.cc): nothing else changes.
#pragma once
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "skycal/bench/case_result.h"

namespace skycal::bench {

struct SuiteOptions {
  bool quick = false;  // CI sizes: every suite in seconds, not minutes
  int repeat = 0;      // timed repeats per case; 0: the suite's own default
  int warmup = 1;      // untimed runs before the repeats
  // The verbs a suite runs (capture, export) print their own progress lines; off, only the
  // suite's own lines (`skycal bench --verb-logs`).
  bool verb_logs = false;
  std::filesystem::path scratch;  // a directory the suite may write temporaries into
  std::function<void(const std::string&)> log;        // progress lines (may be empty)
  std::function<void(const CaseResult&)> on_case;     // called as each case finishes (may be empty)
  // Called as each case starts, with its suite, name, settings and is_default filled in
  // (may be empty): an isolated run's journal (isolated_run.h) records what was running
  // when a worker died.
  std::function<void(const CaseResult&)> on_case_start;
  // Case names not to run (measured, or crashed, by an earlier worker of the same run).
  std::set<std::string> skip;

  bool IsValid(std::string* why) const;
  int Repeats(int suite_default) const { return repeat > 0 ? repeat : suite_default; }
  void Log(const std::string& line) const { if (log) log(line); }
  void Done(const CaseResult& c) const { if (on_case) on_case(c); }
  void Started(const CaseResult& c) const { if (on_case_start) on_case_start(c); }
  bool Skips(const std::string& name) const { return skip.count(name) > 0; }
};

struct Suite {
  std::string name;
  std::string summary;       // one line: what is measured, at which sizes
  std::string error_metric;  // what `error` is, with units ("rel RMSE vs CPU 4096x2048")
  std::string error_axis;    // the same, short, for the plot's y axis
  bool pareto = true;        // time against error is meaningful (not for stress)
  std::function<std::vector<CaseResult>(const SuiteOptions&)> run;
  // Optional: a readable table of the suite's cases (Markdown), written as DIR/<name>.md --
  // what a retired study program wrote (fit-skies: bench_fit's per-sky table; fit-probe:
  // bench_probe_fit's probe-weight table). Empty: none.
  std::function<std::string(const std::vector<CaseResult>&)> markdown;
};

class SuiteRegistry {
 public:
  void Add(Suite suite);  // throws skycal::Error on a duplicate or empty name
  const Suite* Find(const std::string& name) const;
  std::vector<std::string> Names() const;
  // "render,fit" -> the suites, in the order given; throws skycal::Error naming an
  // unknown suite and listing the valid names.
  std::vector<const Suite*> Resolve(const std::string& comma_list) const;

 private:
  std::vector<Suite> suites_;
};

// render, fit, fit-day, fit-cie, fit-cie-study, fit-decisions, fit-skies, fit-probe, fit-clouds,
// fit-clouds-process, fit-cloud-stats, cloud-stats-noise, batch, probe, capture, sky-segmentation,
// capture-chart, capture-stars, capture-response, export, stress, clouds, weather-inversion (suites.cc).
SuiteRegistry BuiltinSuites();

}  // namespace skycal::bench
