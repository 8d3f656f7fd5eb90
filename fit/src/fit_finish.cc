#include "fit_finish.h"

#include <algorithm>
#include <cmath>

namespace skycal::fit {
namespace {
constexpr double kHeldLogChange = -9.2;  // ln(1e-4): this far below the data's level an entry sits at its floor

// Whether the Rayleigh or Mie table t is vanishing in the start's row for channel ch
// (FitState::kVanishingTable).
bool VanishingInStart(const FitState& s, int t, int row, int ch) {
  if (t > 1) return false;
  const int n_gamma = s.preset.luts.grid.n_gamma;
  double largest[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k)
    for (int col = 0; col < n_gamma; ++col) largest[k] = std::max(largest[k], std::exp(s.initial_log_lut[s.Index(k, row, col, ch)]));
  return FitState::Vanishing(largest[t], largest[1 - t]);
}
}  // namespace

int ExtrapolateUnobservedColumns(const std::set<std::pair<int, int>>& observed, const std::vector<bool>& row_fitted,
                                 FitState* state) {
  const auto& grid = state->preset.luts.grid;
  int extrapolated = 0;
  for (int t = 0; t < state->tables; ++t) {
    for (int col = 0; col < grid.n_gamma; ++col) {
      if (observed.count({t, col})) continue;
      int nearest = -1;
      for (int d = 1; d < grid.n_gamma && nearest < 0; ++d) {
        if (col + d < grid.n_gamma && observed.count({t, col + d})) nearest = col + d;
        else if (col - d >= 0 && observed.count({t, col - d})) nearest = col - d;
      }
      if (nearest < 0) continue;
      for (int row = 0; row < grid.n_theta; ++row) {
        if (!row_fitted[row]) continue;
        for (int ch = 0; ch < 3; ++ch) {
          const size_t k = state->Index(t, row, col, ch), kn = state->Index(t, row, nearest, ch);
          // A table the start makes vanishing has a shape nothing in the start's own sky shows
          // (the Mie at twilight: 1e-4 of the Rayleigh, its columns varying 1,000x): the nearest
          // column's value, not its change on that shape (which drew a bright line along a
          // hidden horizon under a twilight glow, bench/results/horizon_columns.md).
          const bool vanishing = VanishingInStart(*state, t, row, ch);
          state->log_lut[k] = vanishing ? state->log_lut[kn]
                                        : state->initial_log_lut[k] + (state->log_lut[kn] - state->initial_log_lut[kn]);
        }
      }
      ++extrapolated;
    }
  }
  return extrapolated;
}

double MoveScaleGaugeToExposures(const std::vector<bool>& row_fitted, bool fit_overcast, FitState* state) {
  const auto& grid = state->preset.luts.grid;
  std::vector<double> all;
  for (int t = 0; t < state->tables; ++t)
    for (int row = 0; row < grid.n_theta; ++row)
      if (row_fitted[row])
        for (int col = 0; col < grid.n_gamma; ++col)
          for (int ch = 0; ch < 3; ++ch) {
            const size_t k = state->Index(t, row, col, ch);
            all.push_back(state->log_lut[k] - state->initial_log_lut[k]);
          }
  if (all.empty()) return 0.0;
  // Entries held at the linear start's floor (1e-6 of the start rescaled to the data: a
  // table the sky does not need) say nothing about the level: left out. "Held" is relative
  // to the data's level (the 90th percentile of the changes), not to the initial preset:
  // a reference in a camera's raw units (1e-30 cd/m^2 per count, say) changes every entry
  // by far more than the floor's 1e-4 margin.
  std::vector<double> sorted = all;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() * 9 / 10, sorted.end());
  const double held_below = sorted[sorted.size() * 9 / 10] + kHeldLogChange;
  std::vector<double> changes;
  for (double c : all) {
    if (c > held_below) changes.push_back(c);
  }
  if (changes.empty()) return 0.0;
  std::nth_element(changes.begin(), changes.begin() + changes.size() / 2, changes.end());
  const double shift = changes[changes.size() / 2];
  for (int t = 0; t < state->tables; ++t)
    for (int row = 0; row < grid.n_theta; ++row)
      if (row_fitted[row])
        for (size_t k = state->Index(t, row, 0, 0); k < state->Index(t, row, 0, 0) + grid.n_gamma * 3; ++k)
          state->log_lut[k] -= shift;
  if (fit_overcast) state->log_overcast_zenith -= shift;
  for (double& e : state->log_exposure) e += shift;
  return shift;
}

}  // namespace skycal::fit
