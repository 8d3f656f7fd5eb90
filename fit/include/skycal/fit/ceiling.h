// The model's own ceiling on a reference: how well the model could fit it at best, in the
// fit's reported error measure (rel_rmse of fit::CompareToReference). "Fit error 2%" means
// little until it is set against this: a fit at its ceiling has done all the model allows.
//
//  - LUT ceiling: the least-squares optimum of the relative error over every LUT entry
//    the reference sees (the two rows around its sun blended, as the fit's tied rows), and
//    L_z when the overcast term is on, for each haziness g (a linear solve: the model is
//    linear in them), minimised over g. Same model variant and LUT grid as the fit.
//  - per-row ceiling: the same with one free value per (table, image row, channel)
//    instead of the LUT columns' interpolation: the model with unlimited LUT columns. The
//    gap between the two is what the LUT's resolution costs on this sky.
// Both on the reference's own pixels (at most 512 wide, as the fit's finest level) with
// the fit's masks. Exposure: 1 (the LUT absorbs the scale). Entries the optimum wants
// <= 0 are held at a small positive floor (the model's LUTs are non-negative).
#pragma once
#include "skycal/fit/fit_options.h"
#include "skycal/fit/reference.h"
#include "skycal/render/preset.h"

namespace skycal::fit {

struct CeilingResult {
  double lut_rel_rmse = 0.0, lut_g = 0.0;
  double per_row_rel_rmse = 0.0, per_row_g = 0.0;
  int width = 0;  // level width it was computed at
  double time_s = 0.0;
};

// `init` gives the grid, variant (from options.variant) and overcast weight; its LUT values
// only seed the floors and the g scan.
CeilingResult ModelCeiling(const Reference& ref, const render::Preset& init, const FitOptions& options);

}  // namespace skycal::fit
