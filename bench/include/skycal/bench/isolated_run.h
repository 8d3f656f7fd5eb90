// Running a suite in a worker process, so that a case which kills its process (a
// segfault, an abort, a sanitizer report, the OOM killer) is recorded as one `crash` case
// instead of ending the whole run.
//
// The parent starts a worker (normally the same executable re-run with the worker's
// command line). The worker appends to a journal, one JSON object per line:
//   {"start": CASE}  before a case's body runs (name, settings, is_default),
//   {"case": CASE}   when it finishes (the full CaseResult, results.h's case schema).
// When the worker ends abnormally inside a case, the parent appends that case as a crash
// and starts a new worker, which skips every case the journal names. A worker that ends
// abnormally outside any case (its suite's preparation) fails the run with a clear error.
#pragma once
#include <filesystem>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "skycal/bench/case_result.h"
#include "skycal/bench/suite.h"

namespace skycal::bench {

struct Journal {
  std::vector<CaseResult> finished;    // in the order they finished
  std::optional<CaseResult> running;   // started, never finished (the worker died in it)
  std::set<std::string> names;         // every case named, started or finished
};

// Reads a journal; an absent file is an empty journal. A torn last line (the worker died
// mid-write) is ignored; any other malformed line throws skycal::Error naming the file.
Journal ReadJournal(const std::filesystem::path& path);

// Worker side: sets options.skip from the journal and chains on_case_start / on_case so
// that each case is appended (and flushed to the kernel) as it starts and finishes.
void AttachJournal(SuiteOptions& options, const std::filesystem::path& path);

struct IsolatedRunOptions {
  std::vector<std::string> worker_argv;  // argv[0]: the executable; the journal is the worker's business
  std::filesystem::path journal;         // shared with the worker (its command line names it)
  int max_restarts = 1000;               // a bound on crashes per suite
  std::function<void(const std::string&)> log;
  bool IsValid(std::string* why) const;
};

// Runs the worker until it exits 0, restarting it after each crash inside a case. Returns
// every case in the order run, crashes included (Outcome::kCrash, the message says how the
// worker ended). Throws skycal::Error when the worker cannot start, ends abnormally outside
// a case, or crashes more than max_restarts times.
std::vector<CaseResult> RunSuiteIsolated(const std::string& suite, const IsolatedRunOptions& options);

}  // namespace skycal::bench
