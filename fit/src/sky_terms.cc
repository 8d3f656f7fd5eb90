#include "sky_terms.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/latlong.h"

namespace skycal::fit {
namespace {

// sqrt(lambda) * (u - u0): pulls a LUT entry toward its initial value (gauge for
// combinations the data cannot separate, e.g. the two LUT rows around one sun angle).
struct PriorResidual {
  double sqrt_lambda, u0;
  template <typename T>
  bool operator()(const T* u, T* r) const {
    r[0] = T(sqrt_lambda) * (u[0] - T(u0));
    return true;
  }
};

// sqrt(lambda) * second difference of the change u - u0 along the sun-zenith axis (log
// space): the change from the initial preset must be smooth, not the LUT itself, so a
// physically shaped start (twilight falls by decades within a few rows) is not flattened.
struct SecondDifferenceOfChange {
  double sqrt_lambda, a0, b0, c0;
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* r) const {
    r[0] = T(sqrt_lambda) * ((a[0] - T(a0)) - T(2.0) * (b[0] - T(b0)) + (c[0] - T(c0)));
    return true;
  }
};

// Wraps a row cost for central-difference Jacobians (the benchmark's baseline).
struct NumericRow {
  const SkyRowCost* cost;
  bool operator()(double const* const* parameters, double* residuals) const {
    return cost->EvaluateCpu(parameters, residuals);
  }
};

}  // namespace

AddedSkyRows AddSkyRowTerms(const SkyRowTerms& in, FitState* state, ceres::Problem* problem) {
  AddedSkyRows out;
  const std::vector<Reference>& refs = *in.refs;
  const std::vector<FitLevel>& levels = *in.levels;
  const int lw = levels.at(0).width, lh = levels.at(0).height;
  for (size_t r = 0; r < refs.size(); ++r) {
    const FitLevel& lv = levels[r];
    for (int y = 0; y < lh; ++y) {
      for (int ch = 0; ch < 3; ++ch) {
        RowCostSetup setup;
        setup.state = state;
        setup.tied_rows = in.tied;
        setup.initial_log_lut = &state->initial_log_lut;
        setup.sun_dir = refs[r].sun_dir;
        setup.channel = ch;
        setup.level_row = y;
        setup.loss = in.loss;
        setup.loss_scale = in.loss_scale;
        setup.rendered = in.rendered ? &(*in.rendered)[r] : nullptr;
        setup.rendered_valid = in.rendered_valid;
        for (int x = 0; x < lw; ++x) {
          const size_t i = static_cast<size_t>(y) * lw + x;
          if (lv.weight[i] <= 0.0) continue;
          const auto v = latlong::PixelDirection(x, y, lw, lh);
          // After the linear start each pixel keeps the loss scale of its ring around the
          // sun (fit/src/linear_start.h: RingLossScales).
          double pixel_scale = 0.0;
          if (in.use_ring_scales) {
            const double d[3] = {v[0] - refs[r].sun_dir[0], v[1] - refs[r].sun_dir[1], v[2] - refs[r].sun_dir[2]};
            const double chord = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            pixel_scale = in.ring_scales[r].At(2.0 * std::asin(std::min(1.0, 0.5 * chord)) * 180.0 / M_PI);
          }
          setup.pixels.push_back({x, std::log(static_cast<double>(lv.radiance[3 * i + ch])),
                                  std::sqrt(lv.weight[i] / in.total_weight), v, pixel_scale});
        }
        if (setup.pixels.empty()) continue;
        out.residuals += static_cast<long long>(setup.pixels.size());
        std::vector<size_t> index;
        auto cost = std::make_unique<SkyRowCost>(std::move(setup), &index);
        std::vector<double*> blocks;
        for (size_t k : index) blocks.push_back(in.tied ? &state->log_delta[k] : &state->log_lut[k]);
        blocks.push_back(&state->g);
        blocks.push_back(&state->log_overcast_zenith);
        blocks.push_back(&state->log_exposure[r]);
        ceres::CostFunction* fn = nullptr;
        if (in.numeric_derivatives) {
          auto* numeric = new ceres::DynamicNumericDiffCostFunction<NumericRow, ceres::CENTRAL>(new NumericRow{cost.get()});
          for (size_t k = 0; k < blocks.size(); ++k) numeric->AddParameterBlock(1);
          numeric->SetNumResiduals(cost->num_residuals());
          out.numeric_owners.push_back(std::move(cost));
          fn = numeric;
        } else {
          fn = cost.release();
        }
        problem->AddResidualBlock(fn, nullptr, blocks);
        for (size_t k = 0; k < index.size(); ++k) out.texel_blocks.insert(blocks[k]);
      }
    }
  }
  return out;
}

long long AddLutPriorTerms(const std::set<std::pair<int, int>>& observed_columns, const std::vector<bool>& row_fitted,
                           bool tied, double prior_weight, double smoothness, FitState* state, ceres::Problem* problem) {
  long long residuals = 0;
  const auto& grid = state->preset.luts.grid;
  const std::vector<double>& initial_log_lut = state->initial_log_lut;
  for (const auto& [t, col] : observed_columns) {
    for (int ch = 0; ch < 3; ++ch) {
      if (tied) {
        double* d = &state->log_delta[state->DeltaIndex(t, col, ch)];
        problem->AddResidualBlock(
            new ceres::AutoDiffCostFunction<PriorResidual, 1, 1>(new PriorResidual{std::sqrt(prior_weight), 0.0}), nullptr, d);
        ++residuals;
        continue;
      }
      for (int row = 0; row < grid.n_theta; ++row) {
        if (!row_fitted[row]) continue;
        double* u = &state->log_lut[state->Index(t, row, col, ch)];
        problem->AddResidualBlock(new ceres::AutoDiffCostFunction<PriorResidual, 1, 1>(new PriorResidual{
                                      std::sqrt(prior_weight), initial_log_lut[u - state->log_lut.data()]}),
                                  nullptr, u);
        ++residuals;
        if (row >= 1 && row + 1 < grid.n_theta && row_fitted[row - 1] && row_fitted[row + 1] && smoothness > 0.0) {
          const ptrdiff_t stride = static_cast<ptrdiff_t>(grid.n_gamma) * 3;
          const size_t k = static_cast<size_t>(u - state->log_lut.data());
          problem->AddResidualBlock(new ceres::AutoDiffCostFunction<SecondDifferenceOfChange, 1, 1, 1, 1>(
                                        new SecondDifferenceOfChange{std::sqrt(smoothness), initial_log_lut[k - stride],
                                                                     initial_log_lut[k], initial_log_lut[k + stride]}),
                                    nullptr, u - stride, u, u + stride);
          ++residuals;
        }
      }
    }
  }
  return residuals;
}

long long SkyRowsTerm::AddTo(ceres::Problem& problem, FitState& state, const LevelContext& level) {
  SkyRowTerms rows;
  rows.refs = level.refs;
  rows.levels = level.levels;
  rows.total_weight = level.total_weight;
  rows.tied = s_.tied;
  rows.loss = s_.loss;
  rows.loss_scale = level.loss_scale;
  rows.numeric_derivatives = s_.numeric_derivatives;
  rows.rendered = level.rendered;
  rows.rendered_valid = level.rendered_valid;
  rows.ring_scales = s_.ring_scales;
  rows.use_ring_scales = s_.use_ring_scales;
  AddedSkyRows added = AddSkyRowTerms(rows, &state, &problem);
  numeric_owners_ = std::move(added.numeric_owners);
  // Regularisation needs the LUT parameters some pixel reaches; columns no pixel reaches
  // (the lowest, horizon-hugging ones at coarse sizes) are filled in after the solve from
  // their nearest observed column (fit_finish.h): as free parameters held only by a weak
  // prior they made the normal equations nearly singular and Levenberg-Marquardt slow.
  const auto& grid = state.preset.luts.grid;
  const size_t table_size = state.preset.luts.table_size();
  observed_columns_.clear();
  for (double* b : added.texel_blocks) {
    const size_t k = s_.tied ? static_cast<size_t>(b - state.log_delta.data())
                             : static_cast<size_t>(b - state.log_lut.data());
    const int col = static_cast<int>((k / 3) % grid.n_gamma);
    const int table = s_.tied ? static_cast<int>(k / (3 * grid.n_gamma)) : static_cast<int>(k / table_size);
    observed_columns_.insert({table, col});
  }
  last_residuals_ = added.residuals;
  return added.residuals;
}

long long LutPriorTerm::AddTo(ceres::Problem& problem, FitState& state, const LevelContext& /*level*/) {
  return AddLutPriorTerms(s_.sky->observed_columns(), s_.row_fitted, s_.tied, s_.prior_weight, s_.smoothness, &state,
                          &problem);
}

}  // namespace skycal::fit
