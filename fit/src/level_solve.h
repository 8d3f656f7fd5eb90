// One pyramid level of the fit's Ceres problem: the level images, the problem built from
// the fit's terms (fit_term.h), the bounds and held blocks of the shared parameters, the
// exposure gauge, the solver options, and the level's report.
#pragma once
#include <chrono>
#include <string>
#include <vector>

#include "fit_state.h"
#include "fit_term.h"
#include "skycal/fit/fit_report.h"
#include "skycal/fit/reference.h"
#include "skycal/render/renderer.h"

namespace skycal::fit {

struct LevelSolveOptions {
  int width = 0;                  // level width, pixels (height width / 2)
  size_t index = 0, count = 1;    // this level's number among `count`, coarse to fine
  double loss_scale = 0.05;       // the level's robust scale, natural-log units
  bool render_in_loop = false;    // the backend renders the model at every new point (Vulkan)
  bool fit_haziness = true, fit_overcast = false, absolute = false;
  bool after_linear_start = false;  // the polish of a linear start (its stopping rule)
  int max_iterations = 50;
  bool verbose = false;
  std::chrono::steady_clock::time_point start;  // of the fit, for the progress log
  std::vector<double*> held;      // parameters held at their floor by the linear start

  bool IsValid(std::string* why) const;
};

// Builds the level's problem from `terms` (in order), solves it, lets each term finish
// (AfterSolve) and reports. Throws skycal::Error when Ceres fails.
LevelReport SolveLevel(const std::vector<FitTerm*>& terms, const std::vector<Reference>& refs,
                       const LevelSolveOptions& options, render::SkyRenderer& renderer, FitState* state);

}  // namespace skycal::fit
