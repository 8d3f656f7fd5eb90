// The sky's terms of the fit's Ceres problem (the polish after the linear start, or the
// old coarse-to-fine path): each adds its parameter blocks and residual blocks to one
// problem, beside the probe's (probe_terms.h).
//  - AddSkyRowTerms: one SkyRowCost per (reference, level row, channel) with fitted pixels
//    (sky_row_cost.h); rows below the horizon or fully masked have no block at all.
//  - AddLutPriorTerms: the weak pull of each LUT parameter some pixel reaches toward the
//    initial preset and, with free rows, the second difference of the change along the
//    sun zenith; columns no pixel reaches are not parameters (fit_finish.h fills them).
// SkyRowsTerm and LutPriorTerm are the two as FitTerms (fit_term.h).
#pragma once
#include <ceres/ceres.h>

#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "fit_state.h"
#include "fit_term.h"
#include "linear_start.h"
#include "pyramid.h"
#include "sky_row_cost.h"
#include "skycal/fit/reference.h"

namespace skycal::fit {

struct SkyRowTerms {
  const std::vector<Reference>* refs = nullptr;
  const std::vector<FitLevel>* levels = nullptr;  // one per reference, same size
  double total_weight = 0.0;                      // sum of the levels' fitted solid angle
  bool tied = false;                              // one reference: tied rows (sky_row_cost.h)
  RobustLoss loss = RobustLoss::kCauchy;
  double loss_scale = 0.05;                       // natural-log units
  bool use_ring_scales = false;                   // per-pixel scales by distance from the sun
  std::vector<RingLossScales> ring_scales;        // one per reference (with use_ring_scales)
  bool numeric_derivatives = false;               // central differences (the baseline)
  const std::vector<ImageRGB>* rendered = nullptr;  // Vulkan: the model images, per reference
  const bool* rendered_valid = nullptr;
};

struct AddedSkyRows {
  std::set<double*> texel_blocks;  // LUT parameters some pixel reaches
  long long residuals = 0;
  // The numeric baseline's wrapped costs (owned here: keep alive while the problem is).
  std::vector<std::unique_ptr<SkyRowCost>> numeric_owners;
};

AddedSkyRows AddSkyRowTerms(const SkyRowTerms& in, FitState* state, ceres::Problem* problem);

// Returns the number of residuals added.
long long AddLutPriorTerms(const std::set<std::pair<int, int>>& observed_columns, const std::vector<bool>& row_fitted,
                      bool tied, double prior_weight, double smoothness, FitState* state, ceres::Problem* problem);

// The sky pixels of every reference, as one term: a SkyRowCost per (reference, level row,
// channel) with fitted pixels.
class SkyRowsTerm final : public FitTerm {
 public:
  struct Setup {
    bool tied = false;
    RobustLoss loss = RobustLoss::kCauchy;
    bool numeric_derivatives = false;
    bool use_ring_scales = false;               // after the linear start
    std::vector<RingLossScales> ring_scales;    // one per reference (with use_ring_scales)
  };
  explicit SkyRowsTerm(Setup setup) : s_(std::move(setup)) {}
  std::string name() const override { return "sky rows"; }
  long long AddTo(ceres::Problem& problem, FitState& state, const LevelContext& level) override;
  // (table, LUT column) pairs some fitted pixel of the last level reads.
  const std::set<std::pair<int, int>>& observed_columns() const { return observed_columns_; }
  long long last_residuals() const { return last_residuals_; }  // of the last level

 private:
  Setup s_;
  std::set<std::pair<int, int>> observed_columns_;
  long long last_residuals_ = 0;
  std::vector<std::unique_ptr<SkyRowCost>> numeric_owners_;  // the baseline's wrapped costs
};

// The LUT priors on the parameters the sky rows reach (AddLutPriorTerms).
class LutPriorTerm final : public FitTerm {
 public:
  struct Setup {
    const SkyRowsTerm* sky = nullptr;  // its observed columns (added before this term)
    std::vector<bool> row_fitted;
    bool tied = false;
    double prior_weight = 1e-8, smoothness = 1e-6;
  };
  explicit LutPriorTerm(Setup setup) : s_(std::move(setup)) {}
  std::string name() const override { return "LUT priors"; }
  long long AddTo(ceres::Problem& problem, FitState& state, const LevelContext& level) override;

 private:
  Setup s_;
};

}  // namespace skycal::fit
