// What every suite does around one case (private to skycal_bench).
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skycal/bench/suite.h"
#include "skycal/render/renderer.h"

namespace skycal::bench {

// Runs `body` for the case at `settings` (index k of n) and returns its result: a
// skycal::Error thrown by body becomes Outcome::kClearError with its message, any other
// exception Outcome::kCrash. Calls options.Started before and options.Done after, and logs
// one progress line. Nothing (and nothing run) for a case in options.skip.
std::optional<CaseResult> RunCase(const std::string& suite, const Settings& settings, const Settings& defaults, int k, int n,
                   const SuiteOptions& options, const std::function<void(CaseResult&)>& body);

// Every case of `grid`, measured by `body`.
std::vector<CaseResult> RunGrid(const std::string& suite, const Grid& grid, const SuiteOptions& options,
                                const std::function<void(CaseResult&)>& body);

std::string FormatG(double v, int digits = 3);  // %.*g
std::string FormatFixed(double v, int decimals);  // %.*f

// The median of v (the mean of the middle two for an even count); NaN when v is empty.
double Median(std::vector<double> v);

// A Markdown table of `cases`, one row each: the case's name, its median time (ms) and
// error, then one column per (header, value) pair; values from `extra` via ExtraNumber.
struct TableColumn {
  std::string header;
  std::function<std::string(const CaseResult&)> value;
};
std::string CaseTable(const std::vector<CaseResult>& cases, const std::string& error_header,
                      const std::vector<TableColumn>& columns);
// extra[key] as %.4g (scaled by `scale`, e.g. 100 for %), "-" when absent or not a number.
std::string ExtraNumber(const CaseResult& c, const std::string& key, double scale = 1.0);

// Runs args[0] with args[1..] (stdout and stderr to /dev/null) and waits for it: a user's
// whole process, start-up and file writes included. Returns its CPU time (user + system,
// seconds, from wait4's rusage). Throws skycal::Error naming `who` and the command unless it
// exits 0.
double RunProcessCpuS(const std::string& who, std::vector<std::string> args);
// This binary's path (/proc/self/exe: the suites that run `skycal` itself); throws
// skycal::Error naming `who` when it cannot be read.
std::string SelfExecutable(const std::string& who);

// One sky renderer per backend, keyed by the `backend` axis' values ("cpu", "vulkan").
std::map<std::string, std::unique_ptr<render::SkyRenderer>> SkyRenderersByBackend();

}  // namespace skycal::bench
