// The fit's hand-written Jacobians against ceres::GradientChecker (central differences),
// for both variants, every robust loss, with and without the overcast term.
#include <gtest/gtest.h>

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>

#include <algorithm>
#include <random>

#include "fit_state.h"
#include "sky_row_cost.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/fit_options.h"
#include "test_presets.h"

namespace skycal::fit {
namespace {

// A cost whose Jacobian for one parameter block is 1% too large: proves the gradient
// check can fail (Ceres' own gradient_checker_test pairs a good and a bad term the same way).
class WrongJacobian final : public ceres::CostFunction {
 public:
  WrongJacobian(const ceres::CostFunction* good, int block) : good_(good), block_(block) {
    set_num_residuals(good->num_residuals());
    *mutable_parameter_block_sizes() = good->parameter_block_sizes();
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (!good_->Evaluate(parameters, residuals, jacobians)) return false;
    if (jacobians && jacobians[block_]) {
      for (int i = 0; i < num_residuals(); ++i) jacobians[block_][i] *= 1.01;
    }
    return true;
  }

 private:
  const ceres::CostFunction* good_;
  int block_;
};

void CheckRow(render::ModelVariant variant, RobustLoss loss, double overcast_weight, int channel, double elevation_row_deg,
              double loss_scale = 0.05, double log_ref_base = std::log(500.0)) {
  render::Preset p = testing::RandomPreset(77, variant);
  p.overcast_weight = overcast_weight;
  FitState st = FitState::FromPreset(p, variant, 1);
  st.g = 0.7;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.3);
  RowCostSetup setup;
  setup.state = &st;
  setup.sun_dir = latlong::DirectionFromElevationAzimuthDeg(23.0, 10.0);
  setup.channel = channel;
  setup.level_row = 0;
  setup.loss = loss;
  setup.loss_scale = loss_scale;
  for (int i = 0; i < 40; ++i) {
    const auto v = latlong::DirectionFromElevationAzimuthDeg(elevation_row_deg, -180.0 + 9.0 * i);
    // Reference = something near the model so residuals span small and large (outliers).
    setup.pixels.push_back({i, log_ref_base + noise(rng), 0.02 + 0.001 * i, v});
  }
  std::vector<size_t> index;
  SkyRowCost cost(setup, &index);
  std::vector<double> values;
  for (size_t k : index) values.push_back(st.log_lut[k] + 0.1 * noise(rng));
  values.push_back(0.7);             // g
  values.push_back(std::log(3000));  // log L_z
  values.push_back(0.3);             // log exposure
  std::vector<const double*> params;
  for (double& v : values) params.push_back(&v);
  std::vector<double> res(cost.num_residuals());
  ASSERT_TRUE(cost.Evaluate(params.data(), res.data(), nullptr)) << "plain evaluation failed, " << params.size() << " blocks, sizes " << cost.parameter_block_sizes().size();
  ceres::NumericDiffOptions nd;
  nd.ridders_relative_initial_step_size = 1e-4;  // keep g inside its domain [0, 1)
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(&cost, no_manifolds, nd);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(params.data(), 1e-6, &results)) << results.error_log;
  EXPECT_LT(results.maximum_relative_error, 1e-6);
  // Control: the same check must fail on a Jacobian 1% off in one block (the g column,
  // whose derivative comes from the Jet instantiation of the shared source).
  WrongJacobian wrong(&cost, static_cast<int>(index.size()));
  ceres::GradientChecker wrong_checker(&wrong, no_manifolds, nd);
  ceres::GradientChecker::ProbeResults wrong_results;
  EXPECT_FALSE(wrong_checker.Probe(params.data(), 1e-6, &wrong_results));
  EXPECT_GT(wrong_results.maximum_relative_error, 1e-3);
}

TEST(FitCost, JacobiansMatchNumericDifferences) {
  for (auto variant : {render::ModelVariant::kFfxv, render::ModelVariant::kFfxvIso}) {
    for (auto loss : {RobustLoss::kNone, RobustLoss::kCauchy, RobustLoss::kHuber}) {
      for (double w : {0.0, 0.35}) {
        for (int ch : {0, 2}) {
          SCOPED_TRACE(std::string(render::ToString(variant)) + " loss " + std::to_string(static_cast<int>(loss)) +
                       " overcast " + std::to_string(w) + " channel " + std::to_string(ch));
          if (loss == RobustLoss::kHuber) {
            // Huber's rho has a kink in its second derivative at |e| = scale, where central
            // differences are O(h) off: probe entirely in the quadratic and linear parts.
            CheckRow(variant, loss, w, ch, 12.0, 50.0);
            CheckRow(variant, loss, w, ch, 0.4, 0.01, -10.0);  // |e| >= ~15: all linear
            continue;
          }
          CheckRow(variant, loss, w, ch, 12.0);
          CheckRow(variant, loss, w, ch, 0.4);  // next to the horizon: steep sqrt column mapping
        }
      }
    }
  }
}

// Ceres style: the field, its value and the expectation; never a command-line flag.
TEST(FitOptions, IsValidNamesTheFieldAndItsValue) {
  std::string why;
  EXPECT_TRUE(FitOptions{}.IsValid(&why)) << why;
  FitOptions o;
  o.sun_cone_deg = -3.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "FitOptions::sun_cone_deg = -3 (expected degrees in [0, 45])");
  o = FitOptions{};
  o.probe_quadrature_width = 130;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "FitOptions::probe_quadrature_width = 130 (expected a lat-long width in [16, 2048] pixels, a multiple of 4)");
  o = FitOptions{};
  o.time_of_day_h = 24.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "FitOptions::time_of_day_h = 24 (expected hours in [0, 24))");
  o = FitOptions{};
  o.unseen_profile = -1e-4;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "FitOptions::unseen_profile = -0.0001 (expected a weight in [0, 1e6])");
}

// The start's LUT (FitState::StartDarkRowsFlat): a fitted row the model leaves partly dark
// (the Earth's shadow: some Rayleigh or Mie entry zero) starts flat at the zero entries'
// floor, every table; every other row is FromPreset's, to the bit: fitted rows whose Mie is
// 0.1% and 5% of their Rayleigh (a tiny table keeps its shape: the model's own twilight sky is
// fitted from it exactly), and a dark row the fit does not solve (the preset's held rows are
// written as they came). The control: the dark row as the preset has it spans many orders of
// magnitude between its tiny entries and the floored zeros beside them.
TEST(FitState, FittedRowsTheEarthsShadowDarkensStartFlat) {
  render::Preset p = testing::RandomPreset(5, render::ModelVariant::kFfxvIso);
  const auto& grid = p.luts.grid;
  const size_t row_size = static_cast<size_t>(grid.n_gamma) * 3, table = p.luts.table_size();
  const int shadow = grid.n_theta - 3, faint = grid.n_theta - 5, hazy = grid.n_theta - 7, held = grid.n_theta - 1;
  const auto max_rayleigh = [&](int row) {
    return *std::max_element(p.luts.rayleigh.begin() + row * row_size, p.luts.rayleigh.begin() + (row + 1) * row_size);
  };
  const double faint_mie = 1e-3 * max_rayleigh(faint), hazy_mie = 0.05 * max_rayleigh(hazy);
  for (size_t i = 0; i < row_size; ++i) {
    const bool dark = i >= row_size / 2;  // the shadow rows' last half zero, the rest 1e-12 of a sky's
    for (int row : {shadow, held}) {
      p.luts.rayleigh[row * row_size + i] = dark ? 0.0f : 1e-9f;
      p.luts.mie[row * row_size + i] = dark ? 0.0f : 1e-12f;
    }
    p.luts.mie[faint * row_size + i] = static_cast<float>(faint_mie);
    p.luts.mie[hazy * row_size + i] = static_cast<float>(hazy_mie);
  }
  const FitState from = FitState::FromPreset(p, render::ModelVariant::kFfxvIso, 1);
  FitState st = from;
  std::vector<bool> rows(grid.n_theta, false);
  rows[shadow] = rows[faint] = rows[hazy] = true;
  st.StartDarkRowsFlat(rows);
  const double floor_value = std::exp(from.log_lut[shadow * row_size + row_size - 1]);
  EXPECT_GT(floor_value / 1e-9, 1e6);  // the control: the cliff the flat start removes
  for (int t = 0; t < 3; ++t)
    for (int row = 0; row < grid.n_theta; ++row)
      for (size_t i = row * row_size; i < (row + 1) * row_size; ++i) {
        const size_t k = t * table + i;
        const double want = row == shadow ? std::log(floor_value) : from.log_lut[k];
        EXPECT_EQ(st.log_lut[k], want) << t << " " << i;
        EXPECT_EQ(st.initial_log_lut[k], want) << t << " " << i;
      }
  EXPECT_LT(from.log_lut[held * row_size], std::log(floor_value) - 10.0);  // held: as the preset has it
}

}  // namespace
}  // namespace skycal::fit
