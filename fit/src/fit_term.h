// The fit's Ceres problem as pluggable terms. A term adds its parameter blocks and residual
// blocks to one level's problem (sky rows, LUT priors, the probe; a cloud-lighting term
// next), may finish its own work after the level's solve, and says what it left out.
// FitSky builds the list once; the level solve (level_solve.h) runs it per pyramid level,
// so a new term plugs in beside the others without editing either.
#pragma once
#include <string>
#include <vector>

#include "fit_state.h"
#include "pyramid.h"
#include "skycal/core/image.h"
#include "skycal/fit/fit_report.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"

namespace ceres {
class Problem;
}

namespace skycal::fit {

// What a term sees of the level being solved.
struct LevelContext {
  const std::vector<Reference>* refs = nullptr;
  const std::vector<FitLevel>* levels = nullptr;  // one per reference, same size
  double total_weight = 0.0;                      // sum of the levels' fitted solid angle (sr)
  size_t index = 0;                               // level number, coarse to fine
  bool first = false, finest = false;
  double loss_scale = 0.05;                       // the level's robust scale, natural-log units
  // Vulkan path: the backend's model images at the current point (per reference, level
  // size) and whether that point could be rendered; null on the CPU path.
  const std::vector<ImageRGB>* rendered = nullptr;
  const bool* rendered_valid = nullptr;
};

class FitTerm {
 public:
  virtual ~FitTerm() = default;
  virtual std::string name() const = 0;
  // Adds the term's parameter blocks and residual blocks (and their bounds) for this
  // level; returns the number of residuals it added.
  virtual long long AddTo(ceres::Problem& problem, FitState& state, const LevelContext& level) = 0;
  // After the level's solve (e.g. the probe's sun refit on the final sky). Returns the
  // iterations of any solve it ran.
  virtual int AfterSolve(FitState& /*state*/, const LevelContext& /*level*/) { return 0; }
  // What the term left out of the fit, and why (appended to fit.json `skipped`/`decisions`).
  virtual void ReportSkips(std::vector<SkipNote>* /*skipped*/, std::vector<FitDecision>* /*decisions*/) const {}
  // After the last level and the gauge move: the term's own part of the result.
  virtual void Summarise(const FitState& /*state*/, FitResult* /*result*/) const {}
};

}  // namespace skycal::fit
