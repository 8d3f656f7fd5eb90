#include "skycal/fit/ceiling.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "fit_state.h"
#include "linear_sky.h"
#include "linear_start.h"
#include "pyramid.h"

namespace skycal::fit {

CeilingResult ModelCeiling(const Reference& ref, const render::Preset& init, const FitOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  FitState state = FitState::FromPreset(init, options.variant, 1);
  state.StartDarkRowsFlat(SunLutRows(init.luts.grid, ref.sun_dir[1]));  // the two rows around the sun, as the fit's
  CeilingResult out;
  const std::vector<int> widths = AutomaticPyramid(ref.radiance.width);
  const FitLevel level = BuildLevel(ref, widths.back());
  out.width = level.width;
  LinearSkyOptions lo;
  lo.fit_overcast = state.preset.overcast_weight > 0.0;
  lo.damping = 1e-10;  // a ceiling: (almost) no regularisation
  for (LinearUnknowns u : {LinearUnknowns::kTiedRows, LinearUnknowns::kPerImageRow}) {
    lo.unknowns = u;
    const LinearSky sky(state, {&level}, {ref}, lo);
    const CeilingReport c = MinimiseOverHaziness(sky, {1.0}, init.haziness_g);
    if (u == LinearUnknowns::kTiedRows) {
      out.lut_rel_rmse = c.rel_rmse;
      out.lut_g = c.g;
    } else {
      out.per_row_rel_rmse = c.rel_rmse;
      out.per_row_g = c.g;
    }
  }
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace skycal::fit
