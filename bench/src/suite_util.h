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

// One sky renderer per backend, keyed by the `backend` axis' values ("cpu", "vulkan").
std::map<std::string, std::unique_ptr<render::SkyRenderer>> SkyRenderersByBackend();

}  // namespace skycal::bench
