#include "probe_cost.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "robust_residual.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"
#include "skycal/render/sky_params.h"
#include "model_structure.h"

namespace skycal::fit {
namespace {

template <typename S>
using Model = StructureModel<S>;

template <typename S>
typename Model<S>::SkyParams GridParams(const FitState& st) {
  return render::SkyParamsFromPreset<typename Model<S>::SkyParams>(st.preset);
}

}  // namespace

// Per evaluation: E (sky only) per normal and channel, the effective LUT values at the sun's
// row per (table, column, channel), and the Mie G matrix and its g derivative.
struct ProbeCost::Irradiance {
  Eigen::MatrixXd e_sky;                 // (N + 1) x 3
  std::vector<double> teff[3];           // [table][col * 3 + ch]
  std::vector<double> slot_value;        // per LUT parameter: its share of teff (= d teff / d parameter)
  Eigen::MatrixXd g_mie, dg_mie;         // (N + 1) x n_gamma
};

ProbeCost::ProbeCost(ProbeCostSetup setup, std::vector<size_t>* texel_index) : setup_(std::move(setup)) {
  const FitState& st = *setup_.state;
  const render::LutGrid& grid = st.preset.luts.grid;
  n_gamma_ = grid.n_gamma;
  qw_ = setup_.quadrature_width;
  const int qh = qw_ / 2;
  rows_ = qh / 2;  // rows above the horizon (qh is even: no row on the horizon)
  NoLut nolut;
  Model<double> m(nolut);
  const auto p = GridParams<double>(st);
  const auto lr = m.lut_row(setup_.sun_dir[1], p);
  row0_ = lr.row0;
  frow_ = lr.frow;

  // LUT parameters: every (table, column) some pixel row reads, per channel.
  for (int y = 0; y < rows_; ++y) {
    const auto v = latlong::PixelDirection(0, y, qw_, qh);
    const auto lc = m.lut_col(v[1], p);
    row_col0_.push_back(lc.col0);
    row_fcol_.push_back(lc.fcol);
  }
  std::set<int> columns_read;
  for (int y = 0; y < rows_; ++y) {
    if (row_fcol_[y] < 1.0) columns_read.insert(row_col0_[y]);
    if (row_fcol_[y] > 0.0) columns_read.insert(row_col0_[y] + 1);
  }
  AddSlots(columns_read, texel_index);
  BuildQuadrature();
  BuildConstantTeff();
  const int n = static_cast<int>(setup_.samples.size());
  const auto& s = setup_.sun_dir;
  for (int i = 0; i < n; ++i) {
    const auto& nn = setup_.samples[i].normal;
    h_.push_back(0.5 * (1.0 - nn[1]));
    cos_sun_.push_back(std::max(0.0, nn[0] * s[0] + nn[1] * s[1] + nn[2] * s[2]));
  }

  set_num_residuals(3 * n);
  for (size_t i = 0; i < slots_.size(); ++i) mutable_parameter_block_sizes()->push_back(1);
  for (int size : {1, 1, 1, 3, 1}) mutable_parameter_block_sizes()->push_back(size);  // g, log Lz, log k, sun, rho_g
}

void ProbeCost::AddSlots(const std::set<int>& columns_read, std::vector<size_t>* texel_index) {
  const FitState& st = *setup_.state;
  const int tables = st.tables;
  const double wr[2] = {1.0 - frow_, frow_};
  texel_index->clear();
  for (int t = 0; t < tables; ++t) {
    for (int col : columns_read) {
      if (!setup_.parameter_columns.count({t, col})) continue;
      for (int ch = 0; ch < 3; ++ch) {
        if (setup_.tied_rows) {
          Slot s{t, col, ch, 0, {0.0, 0.0}, {0.0, 0.0}};
          for (int dr = 0; dr < 2; ++dr) {
            if (wr[dr] <= 0.0) continue;
            s.wrow[s.nrows] = wr[dr];
            s.offset[s.nrows] = (*setup_.initial_log_lut)[st.Index(t, row0_ + dr, col, ch)];
            ++s.nrows;
          }
          slots_.push_back(s);
          texel_index->push_back(st.DeltaIndex(t, col, ch));
        } else {
          for (int dr = 0; dr < 2; ++dr) {
            if (wr[dr] <= 0.0) continue;
            slots_.push_back({t, col, ch, 1, {wr[dr], 0.0}, {0.0, 0.0}});
            texel_index->push_back(st.Index(t, row0_ + dr, col, ch));
          }
        }
      }
    }
  }
}

void ProbeCost::BuildQuadrature() {
  NoLut nolut;
  Model<double> m(nolut);
  const int qh = qw_ / 2;
  // Quadrature weights for every sample normal and the up normal (last row).
  const int n = static_cast<int>(setup_.samples.size());
  const int npix = rows_ * qw_;
  w_.resize(n + 1, npix);
  mu_.resize(npix);
  one_minus_mu_.resize(npix);
  Eigen::VectorXd phase_r(npix), shape(npix);
  const auto& s = setup_.sun_dir;
  for (int y = 0; y < rows_; ++y) {
    for (int x = 0; x < qw_; ++x) {
      const int k = y * qw_ + x;
      const auto v = latlong::PixelDirection(x, y, qw_, qh);
      const double omega = latlong::PixelSolidAngle(x, y, qw_, qh);
      for (int i = 0; i < n; ++i) {
        const auto& nn = setup_.samples[i].normal;
        w_(i, k) = omega * std::max(0.0, nn[0] * v[0] + nn[1] * v[1] + nn[2] * v[2]);
      }
      w_(n, k) = omega * std::max(0.0, v[1]);
      one_minus_mu_[k] = OneMinusMu(v, s);
      mu_[k] = 1.0 - one_minus_mu_[k];
      phase_r[k] = m.phase_rayleigh(mu_[k]);
      shape[k] = OvercastShape(v[1]);
    }
  }
  // Fixed G matrices: Rayleigh and isotropic phases do not depend on g.
  g_rayleigh_ = Eigen::MatrixXd::Zero(n + 1, n_gamma_);
  g_isotropic_ = Eigen::MatrixXd::Zero(n + 1, n_gamma_);
  const Eigen::VectorXd iso = Eigen::VectorXd::Constant(qw_, kIsotropicPhase);
  for (int y = 0; y < rows_; ++y) {
    const Eigen::VectorXd ar = w_.middleCols(y * qw_, qw_) * phase_r.segment(y * qw_, qw_);
    const Eigen::VectorXd ai = w_.middleCols(y * qw_, qw_) * iso;
    g_rayleigh_.col(row_col0_[y]) += (1.0 - row_fcol_[y]) * ar;
    g_rayleigh_.col(row_col0_[y] + 1) += row_fcol_[y] * ar;
    g_isotropic_.col(row_col0_[y]) += (1.0 - row_fcol_[y]) * ai;
    g_isotropic_.col(row_col0_[y] + 1) += row_fcol_[y] * ai;
  }
  a_overcast_ = w_ * shape;
}

void ProbeCost::BuildConstantTeff() {
  const FitState& st = *setup_.state;
  const double wr[2] = {1.0 - frow_, frow_};
  // The LUT at the sun's row position, from the state now: the values of the columns that
  // are not parameters (constants of this block).
  overcast_weight_ = st.preset.overcast_weight;
  for (int t = 0; t < 3; ++t) {
    constant_teff_[t].assign(static_cast<size_t>(n_gamma_) * 3, 0.0);
    if (t >= st.tables) continue;
    for (int col = 0; col < n_gamma_; ++col) {
      for (int ch = 0; ch < 3; ++ch) {
        double v = 0.0;
        for (int dr = 0; dr < 2; ++dr) {
          if (wr[dr] <= 0.0) continue;
          const size_t k = st.Index(t, row0_ + dr, col, ch);
          const double u = setup_.tied_rows ? (*setup_.initial_log_lut)[k] + st.log_delta[st.DeltaIndex(t, col, ch)]
                                            : st.log_lut[k];
          v += wr[dr] * std::exp(u);
        }
        constant_teff_[t][col * 3 + ch] = v;
      }
    }
  }
}

bool ProbeCost::Compute(double const* const* parameters, bool with_derivatives, Irradiance* out) const {
  const int nt = num_texels();
  const double g = parameters[nt][0];
  if (!(g >= 0.0 && g < 1.0)) return false;
  const double lz = std::exp(parameters[nt + 1][0]);
  const int n1 = num_samples() + 1;
  for (int t = 0; t < 3; ++t) out->teff[t] = constant_teff_[t];
  // The parameter columns from the parameters: every row with a weight > 0 is a slot (one
  // slot for both rows when tied), so such a column is rebuilt from its slots alone.
  out->slot_value.assign(nt, 0.0);
  std::vector<bool> reset(static_cast<size_t>(3) * n_gamma_ * 3, false);
  for (int k = 0; k < nt; ++k) {
    const Slot& s = slots_[k];
    const size_t key = (static_cast<size_t>(s.table) * n_gamma_ + s.col) * 3 + s.channel;
    double& dst = out->teff[s.table][s.col * 3 + s.channel];
    if (!reset[key]) dst = 0.0;
    reset[key] = true;
    for (int j = 0; j < s.nrows; ++j) out->slot_value[k] += s.wrow[j] * std::exp(parameters[k][0] + s.offset[j]);
    dst += out->slot_value[k];
  }

  // Mie G(g) and dG/dg.
  const int npix = rows_ * qw_;
  Eigen::VectorXd phase_m(npix), dphase_m(npix);
  for (int k = 0; k < npix; ++k) {
    const MiePhase pm = MiePhaseWithDerivative(mu_[k], one_minus_mu_[k], g);
    phase_m[k] = pm.value;
    dphase_m[k] = pm.d_dg;
  }
  out->g_mie = Eigen::MatrixXd::Zero(n1, n_gamma_);
  out->dg_mie = Eigen::MatrixXd::Zero(n1, with_derivatives ? n_gamma_ : 0);
  for (int y = 0; y < rows_; ++y) {
    const auto block = w_.middleCols(y * qw_, qw_);
    const Eigen::VectorXd am = block * phase_m.segment(y * qw_, qw_);
    out->g_mie.col(row_col0_[y]) += (1.0 - row_fcol_[y]) * am;
    out->g_mie.col(row_col0_[y] + 1) += row_fcol_[y] * am;
    if (with_derivatives) {
      const Eigen::VectorXd dam = block * dphase_m.segment(y * qw_, qw_);
      out->dg_mie.col(row_col0_[y]) += (1.0 - row_fcol_[y]) * dam;
      out->dg_mie.col(row_col0_[y] + 1) += row_fcol_[y] * dam;
    }
  }

  const double w_oc = overcast_weight_;
  out->e_sky.resize(n1, 3);
  for (int ch = 0; ch < 3; ++ch) {
    Eigen::VectorXd tr(n_gamma_), tm(n_gamma_), ti(n_gamma_);
    for (int col = 0; col < n_gamma_; ++col) {
      tr[col] = out->teff[0][col * 3 + ch];
      tm[col] = out->teff[1][col * 3 + ch];
      ti[col] = out->teff[2][col * 3 + ch];
    }
    out->e_sky.col(ch) = (1.0 - w_oc) * (g_rayleigh_ * tr + out->g_mie * tm + g_isotropic_ * ti) + (w_oc * lz) * a_overcast_;
  }
  return true;
}

ProbeIrradianceParts ProbeCost::Parts(double const* const* parameters) const {
  Irradiance irr;
  ProbeIrradianceParts parts;
  if (!Compute(parameters, false, &irr)) return parts;
  const int nt = num_texels(), n = num_samples();
  const double rho_g = parameters[nt + 4][0];
  const double sy = std::max(0.0, setup_.sun_dir[1]);
  for (int i = 0; i < n; ++i) {
    std::array<double, 3> a{};
    for (int c = 0; c < 3; ++c) a[c] = irr.e_sky(i, c) + rho_g * h_[i] * irr.e_sky(n, c);
    parts.ambient.push_back(a);
    parts.sun_factor.push_back(cos_sun_[i] + rho_g * h_[i] * sy);
    parts.sun_direct.push_back(cos_sun_[i]);
  }
  return parts;
}

bool ProbeCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const auto start = std::chrono::steady_clock::now();
  struct AddTime {
    std::chrono::steady_clock::time_point start;
    std::atomic<long long>* sink;
    ~AddTime() {
      if (sink) *sink += std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count();
    }
  } add_time{start, setup_.evaluation_ns};
  Irradiance irr;
  if (!Compute(parameters, jacobians != nullptr, &irr)) return false;
  const int nt = num_texels(), n = num_samples();
  const double lz = std::exp(parameters[nt + 1][0]);
  const double log_k = parameters[nt + 2][0];
  const double* sun = parameters[nt + 3];
  const double rho_g = parameters[nt + 4][0];
  const double sy = std::max(0.0, setup_.sun_dir[1]);
  const double w_oc = overcast_weight_;
  const double log_a_pi = std::log(setup_.albedo / kPi);

  if (jacobians) {
    for (int k = 0; k < nt + 5; ++k) {
      if (jacobians[k]) std::fill(jacobians[k], jacobians[k] + 3 * n * parameter_block_sizes()[k], 0.0);
    }
  }
  for (int i = 0; i < n; ++i) {
    const ProbeResidualSample& smp = setup_.samples[i];
    for (int c = 0; c < 3; ++c) {
      const int row = 3 * i + c;
      const double e_up = irr.e_sky(n, c);
      const double e = irr.e_sky(i, c) + sun[c] * cos_sun_[i] + rho_g * h_[i] * (e_up + sun[c] * sy);
      if (!(e > 0.0) || !std::isfinite(e)) return false;
      const double err = log_k + log_a_pi + std::log(e) - smp.log_radiance[c];
      const RobustResidual rr = MakeRobustResidual(setup_.loss, setup_.loss_scale, smp.sqrt_weight, err);
      residuals[row] = rr.r;
      if (!jacobians) continue;
      const double d = rr.dr_de / e;  // dr/dE
      const double ground = rho_g * h_[i];
      for (int k = 0; k < nt; ++k) {
        const Slot& s = slots_[k];
        if (s.channel != c || !jacobians[k]) continue;
        const double t = irr.slot_value[k];
        const Eigen::MatrixXd& gm = s.table == 0 ? g_rayleigh_ : s.table == 1 ? irr.g_mie : g_isotropic_;
        jacobians[k][row] = d * (1.0 - w_oc) * t * (gm(i, s.col) + ground * gm(n, s.col));
      }
      if (jacobians[nt]) {
        double de_dg = 0.0;
        for (int col = 0; col < n_gamma_; ++col) {
          de_dg += irr.teff[1][col * 3 + c] * (irr.dg_mie(i, col) + ground * irr.dg_mie(n, col));
        }
        jacobians[nt][row] = d * (1.0 - w_oc) * de_dg;
      }
      if (jacobians[nt + 1]) jacobians[nt + 1][row] = d * w_oc * lz * (a_overcast_[i] + ground * a_overcast_[n]);
      if (jacobians[nt + 2]) jacobians[nt + 2][row] = rr.dr_de;
      if (jacobians[nt + 3]) jacobians[nt + 3][row * 3 + c] = d * (cos_sun_[i] + ground * sy);
      if (jacobians[nt + 4]) jacobians[nt + 4][row] = d * h_[i] * (e_up + sun[c] * sy);
    }
  }
  return true;
}

}  // namespace skycal::fit
