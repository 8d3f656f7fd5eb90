#include "sky_row_cost.h"

#include <cmath>

#include "model_structure.h"
#include "robust_residual.h"
#include "skycal/render/sky_model.h"
#include "skycal/render/sky_params.h"

namespace skycal::fit {
namespace {

// LUT source over the few texels of one row block and one channel: texel (row0 + dr,
// col0 + dc) of table t is values[t][dr][dc], replicated over r, g, b.
struct BlockLut {
  int row0 = 0, col0 = 0;
  double values[3][2][2] = {};
  template <typename S>
  glsl::Vec3<S> texel(int lut, int row, int col) const {
    const int dr = row - row0, dc = col - col0;
    const double v = (dr >= 0 && dr < 2 && dc >= 0 && dc < 2) ? values[lut][dr][dc] : 0.0;
    return glsl::Vec3<S>(S(v));
  }
};

template <typename S>
using Model = model::SkyModel<S, BlockLut>;

Model<double>::SkyParams MakeParams(const FitState& st, const std::array<double, 3>& sun, double g, double lz) {
  auto p = render::SkyParamsFromPreset<Model<double>::SkyParams>(st.preset);  // disc and ground radiance 0
  p.sun_dir = glsl::Vec3<double>(sun[0], sun[1], sun[2]);
  p.haziness_g = g;
  p.isotropic_weight = st.tables == 3 ? 1.0 : 0.0;
  p.overcast_zenith = lz;
  p.sun_one_minus_cos_radius = 0.0;
  p.sun_radius = 1.0;
  p.sun_limb_u = 0.0;
  return p;
}

}  // namespace

SkyRowCost::SkyRowCost(RowCostSetup setup, std::vector<size_t>* texel_index) : s_(std::move(setup)) {
  const FitState& st = *s_.state;
  BlockLut lut;
  Model<double> m(lut);
  const auto p = MakeParams(st, s_.sun_dir, st.g, 1.0);
  const auto lr = m.lut_row(p.sun_dir.y, p);
  // Every pixel of the row has the same elevation; take it from the first pixel.
  const auto lc = m.lut_col(s_.pixels.front().view[1], p);
  row0_ = lr.row0;
  col0_ = lc.col0;
  texel_index->clear();
  const double wr[2] = {1.0 - lr.frow, lr.frow};
  const double wc[2] = {1.0 - lc.fcol, lc.fcol};
  for (int t = 0; t < st.tables; ++t) {
    for (int dc = 0; dc < 2; ++dc) {
      if (wc[dc] <= 0.0) continue;  // column not touched: not a parameter of this block
      if (s_.tied_rows) {
        Texel tx{t, dc, wc[dc], 0, {0, 0}, {0.0, 0.0}, {0.0, 0.0}};
        for (int dr = 0; dr < 2; ++dr) {
          if (wr[dr] <= 0.0) continue;
          tx.drow[tx.nrows] = dr;
          tx.wrow[tx.nrows] = wr[dr];
          tx.offset[tx.nrows] = (*s_.initial_log_lut)[st.Index(t, row0_ + dr, col0_ + dc, s_.channel)];
          ++tx.nrows;
        }
        texels_.push_back(tx);
        texel_index->push_back(st.DeltaIndex(t, col0_ + dc, s_.channel));
      } else {
        for (int dr = 0; dr < 2; ++dr) {
          if (wr[dr] <= 0.0) continue;
          texels_.push_back({t, dc, wc[dc], 1, {dr, 0}, {wr[dr], 0.0}, {0.0, 0.0}});
          texel_index->push_back(st.Index(t, row0_ + dr, col0_ + dc, s_.channel));
        }
      }
    }
  }
  for (const RowPixel& px : s_.pixels) {
    const double omm = OneMinusMu(px.view, s_.sun_dir);
    one_minus_mu_.push_back(omm);
    mu_.push_back(1.0 - omm);
    phase_r_.push_back(m.phase_rayleigh(1.0 - omm));
  }
  overcast_shape_ = OvercastShape(s_.pixels.front().view[1]);
  set_num_residuals(static_cast<int>(s_.pixels.size()));
  for (size_t i = 0; i < texels_.size(); ++i) mutable_parameter_block_sizes()->push_back(1);
  for (int i = 0; i < 3; ++i) mutable_parameter_block_sizes()->push_back(1);  // g, log Lz, log k
}

bool SkyRowCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, s_.rendered != nullptr);
}

bool SkyRowCost::EvaluateCpu(double const* const* parameters, double* residuals) const {
  return EvaluateImpl(parameters, residuals, nullptr, false);
}

bool SkyRowCost::EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians,
                              bool use_rendered) const {
  const FitState& st = *s_.state;
  const int nt = static_cast<int>(texels_.size());
  const double g = parameters[nt][0];
  const double lz = std::exp(parameters[nt + 1][0]);
  const double log_k = parameters[nt + 2][0];
  if (!(g >= 0.0 && g < 1.0)) return false;  // outside the model's domain: Ceres shrinks the step
  if (use_rendered && s_.rendered_valid && !*s_.rendered_valid) return false;

  BlockLut lut;
  lut.row0 = row0_;
  lut.col0 = col0_;
  // Per parameter: its rows' values; the bilinear sum it contributes (its derivative with
  // respect to the log parameter, before the phase factor).
  std::vector<double> texel_sum(nt);
  for (int k = 0; k < nt; ++k) {
    const Texel& tx = texels_[k];
    texel_sum[k] = 0.0;
    for (int j = 0; j < tx.nrows; ++j) {
      const double v = std::exp(parameters[k][0] + tx.offset[j]);
      lut.values[tx.table][tx.drow[j]][tx.dcol] = v;
      texel_sum[k] += tx.wcol * tx.wrow[j] * v;
    }
  }
  Model<double> m(lut);
  const auto p = MakeParams(st, s_.sun_dir, g, lz);
  const double w_oc = st.preset.overcast_weight;
  // Bilinear sums of each table (this channel), for the g derivative.
  double table_sum[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < nt; ++k) table_sum[texels_[k].table] += texel_sum[k];

  for (size_t i = 0; i < s_.pixels.size(); ++i) {
    const RowPixel& px = s_.pixels[i];
    const glsl::Vec3<double> view(px.view[0], px.view[1], px.view[2]);
    // The model value: the Vulkan render at this point, or the shared source in double.
    // (Both backends use the same analytic Jacobian below, scaled by 1/value.)
    const double model_value =
        use_rendered ? static_cast<double>(s_.rendered->at(px.x, s_.level_row, s_.channel)) : m.sky_radiance(view, p).x;
    if (!(model_value > 0.0)) return false;
    const double e = log_k + std::log(model_value) - px.log_ref;
    const RobustResidual rr = MakeRobustResidual(s_.loss, px.loss_scale > 0.0 ? px.loss_scale : s_.loss_scale, px.sqrt_weight, e);
    residuals[i] = rr.r;
    if (!jacobians) continue;
    const double dr_de = rr.dr_de;
    const double inv_m = 1.0 / model_value;
    // Phase values of each table at this pixel.
    const MiePhase pm = MiePhaseWithDerivative(mu_[i], one_minus_mu_[i], g);
    const double phase[3] = {phase_r_[i], pm.value, kIsotropicPhase};
    for (int k = 0; k < nt; ++k) {
      if (!jacobians[k]) continue;
      jacobians[k][i] = dr_de * (1.0 - w_oc) * texel_sum[k] * phase[texels_[k].table] * inv_m;
    }
    if (jacobians[nt]) jacobians[nt][i] = dr_de * (1.0 - w_oc) * table_sum[1] * pm.d_dg * inv_m;
    if (jacobians[nt + 1]) jacobians[nt + 1][i] = dr_de * w_oc * lz * overcast_shape_ * inv_m;
    if (jacobians[nt + 2]) jacobians[nt + 2][i] = dr_de;
  }
  return true;
}

}  // namespace skycal::fit
