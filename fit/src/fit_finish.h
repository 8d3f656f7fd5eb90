// The fit's last steps on the state, after the solves (FitSky).
#pragma once
#include <set>
#include <utility>
#include <vector>

#include "fit_state.h"

namespace skycal::fit {

// LUT columns no fitted pixel reaches (view elevations the references do not sample,
// e.g. within ~0.1 deg of the horizon) take, per fitted row, the log change of the nearest
// observed column of the same table. Returns the number of (table, column) pairs filled.
int ExtrapolateUnobservedColumns(const std::set<std::pair<int, int>>& observed, const std::vector<bool>& row_fitted,
                                 FitState* state);

// Exposure x LUT scale is one degree of freedom (the gauge). Moves the median log change
// of the fitted LUT entries onto the exposures, so the LUT keeps the initial preset's
// absolute level; the median, not the mean, of the entries not held near zero (a table
// the sky does not need, log change below ln 1e-4): those do not set the level. L_z moves with the LUT when fitted. Returns the
// shift (natural log); the caller moves anything else in model units (the probe's sun).
double MoveScaleGaugeToExposures(const std::vector<bool>& row_fitted, bool fit_overcast, FitState* state);

}  // namespace skycal::fit
