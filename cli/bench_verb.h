// `skycal bench`: run time against error (and numerical stress) across the pipeline, as
// suites of measured cases (bench/include/skycal/bench/suite.h), written to DIR/results.json,
// DIR/results.csv and a Pareto plot per suite; or `--compare OLD.json NEW.json`: time ratios
// per case, regressions flagged beyond the measured noise.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/bench/suite.h"

namespace skycal::cli {

struct BenchOptions {
  std::string suites;                // "render,fit" (names from the registry)
  bool quick = false;                // CI sizes
  int repeat = 0;                    // timed repeats per case, [1, 1000]; 0: each suite's default
  std::string out;                   // output directory, staged (core/staged_directory.h)
  std::vector<std::string> compare;  // OLD.json NEW.json: compare instead of running
  std::string replot;                // RESULTS.json: redraw its plots (and fronts) into --out, run nothing
  double noise_floor = 0.10;         // --compare: relative noise below which a ratio is not flagged
  // Each suite runs in a worker process started from this executable (a case that kills
  // its process becomes one `crash` case: skycal/bench/isolated_run.h); empty: in this
  // process (library callers and tests). ParseBenchArgs sets /proc/self/exe unless
  // --in-process.
  std::string worker_executable;
  // Worker mode (hidden options; the parent passes them): run the one suite, journaling
  // to worker_journal, with worker_scratch as its scratch directory; no results written.
  std::string worker_journal, worker_scratch;
  bool report = true;                // write DIR/report.html (skycal report)
  bool verb_logs = false;            // --verb-logs: the verbs the suites run (capture, export) log too

  bool IsValid(std::string* why) const;
};

// Runs the suites (or the comparison) and returns the JSON summary. Throws skycal::Error
// on bad options (naming the option), on a results directory that may not be replaced, and
// after writing the results when any case ended non-finite or in a crash.
nlohmann::json RunBenchImpl(const BenchOptions& options, const bench::SuiteRegistry& registry);
BenchOptions ParseBenchArgs(int argc, char** argv);
int RunBench(int argc, char** argv);

}  // namespace skycal::cli
