// The probe term of the joint fit (Forza Horizon 3's gray ball: Wood, GDC; the diffuse
// sphere of Debevec et al., "Capturing Light Probes in the Sun", 2003): one Ceres residual
// block per probed reference, one residual per (probe sample, channel).
//
// Prediction of the ball's radiance for sample i (normal n_i) and channel c:
//   P_ic  = k * a / pi * E_ic                       (k: the reference's exposure, a: ball albedo)
//   E_ic  = E_sky,c(n_i) + S_c max(0, n_i.s) + rho_g h_i (E_sky,c(up) + S_c max(0, s_y))
// with S the sun's illuminance at normal incidence (a parameter block of 3, model units),
// rho_g the ground albedo (a parameter), h_i = (1 - n_i,y) / 2 the fraction of a uniform
// lower hemisphere a plane of normal n_i sees (pi L_ground h_i is its irradiance: the
// standard view factor), and E_sky the model sky's irradiance by quadrature over the upper
// half of a quadrature_width x quadrature_width/2 lat-long (core/latlong.h nodes):
//   E_sky,c(n) = sum_p omega_p max(0, n.v_p) L_c(v_p).
// The ground is the renderer's (render/src/resolved_sky.cc, GroundMode::kLit): a uniform
// Lambertian plane lit by the sun and the sky, so the ground light follows the fitted sun.
//
// Residual: e_ic = log P_ic - log R_ic, robust and weighted exactly like the sky rows
// (robust_residual.h), so probe and sky errors are both relative errors of the same frame.
//
// Derivatives are analytic. The model is linear in the LUT entries: with G^t_i,col = the
// quadrature of max(0, n_i.v) * phase_t(v) * (bilinear column weight of col at v's
// elevation) over the sky, E_sky = (1 - w_oc) sum_t,col G^t_i,col T_t,col(sun row) +
// w_oc L_z A^oc_i, and d/d(log T) = T d/dT. G for Rayleigh and isotropic is fixed; the Mie
// G and dG/dg are recomputed per evaluation (one matrix-vector product per pixel row).
// Values come from the same decomposition (the shared model source's phase functions and
// LUT coordinates, in double); tests/probe_cost_test.cc checks it against the quadrature of
// CPU and Vulkan renders of the same sky (1e-6 and 2e-5: float pixels).
//
// LUT entries that are not parameters of the block are constants taken from the state when
// the block is built (the joint fit builds its probe blocks at the start of each level and
// once more on the final sky: fit/src/probe_terms.h).
#pragma once
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <set>
#include <utility>
#include <vector>

#include "fit_state.h"
#include "skycal/core/image.h"
#include "skycal/fit/fit_options.h"

namespace skycal::fit {

struct ProbeResidualSample {
  std::array<double, 3> normal{};        // unit, world frame (+Y up)
  std::array<double, 3> log_radiance{};  // natural log of the measured ball radiance per channel
  double sqrt_weight = 0.0;              // see FitOptions::probe_weight
};

struct ProbeCostSetup {
  const FitState* state = nullptr;   // grid, variant, overcast weight, the constant LUT entries (read when built)
  bool tied_rows = false;            // as RowCostSetup::tied_rows
  const std::vector<double>* initial_log_lut = nullptr;
  std::array<double, 3> sun_dir{};   // unit
  double albedo = 0.18;              // the ball's diffuse albedo
  std::vector<ProbeResidualSample> samples;
  RobustLoss loss = RobustLoss::kCauchy;
  double loss_scale = 0.05;
  int quadrature_width = 128;        // lat-long width of the sky quadrature (height = width / 2)
  // (table, column) pairs whose LUT entries are parameters of this block; the other
  // columns enter with their values in `state` when the block is built.
  std::set<std::pair<int, int>> parameter_columns;
  std::atomic<long long>* evaluation_ns = nullptr;  // optional: time spent in Evaluate is added here
};

// The prediction split for the linear sun start and the report:
//   E_i = ambient_i + S * sun_factor_i  (per channel), sun_direct_i = max(0, n_i . s).
struct ProbeIrradianceParts {
  std::vector<std::array<double, 3>> ambient;  // sky + the sky's share of the ground light
  std::vector<double> sun_factor;              // max(0, n.s) + rho_g h max(0, s_y)
  std::vector<double> sun_direct;              // max(0, n.s)
};

class ProbeCost final : public ceres::CostFunction {
 public:
  // Parameter blocks in order: the LUT parameters (`texel_index` receives their
  // FitState::log_lut or FitState::DeltaIndex indices), then g, log L_z, log exposure (1
  // each), the sun's RGB illuminance (3), the ground albedo (1).
  ProbeCost(ProbeCostSetup setup, std::vector<size_t>* texel_index);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  // Irradiance parts at `parameters` (same blocks as Evaluate), by the CPU decomposition.
  ProbeIrradianceParts Parts(double const* const* parameters) const;
  int num_texels() const { return static_cast<int>(slots_.size()); }
  int num_samples() const { return static_cast<int>(setup_.samples.size()); }

 private:
  // One LUT parameter (a table, column and channel, and its one or two rows).
  struct Slot {
    int table, col, channel, nrows;
    double wrow[2], offset[2];
  };
  struct Irradiance;  // per evaluation (probe_cost.cc)
  bool Compute(double const* const* parameters, bool with_derivatives, Irradiance* out) const;
  // The constructor's stages: the LUT parameters (slots) of the columns the pixel rows
  // read, the quadrature (w_, the phases, the fixed G matrices, a_overcast_), and the
  // LUT at the sun's row from the state (constant_teff_).
  void AddSlots(const std::set<int>& columns_read, std::vector<size_t>* texel_index);
  void BuildQuadrature();
  void BuildConstantTeff();

  ProbeCostSetup setup_;
  double overcast_weight_ = 0.0;
  std::vector<double> constant_teff_[3];  // [table][col * 3 + ch]: LUT at the sun's row, from the state when built
  int n_gamma_ = 0, row0_ = 0, qw_ = 0, rows_ = 0;  // rows_: pixel rows above the horizon
  double frow_ = 0.0;
  std::vector<int> row_col0_;      // per pixel row: the LUT column pair's first column
  std::vector<double> row_fcol_;   // and the second's weight
  std::vector<Slot> slots_;
  Eigen::MatrixXd w_;              // (N + 1) x P: omega_p max(0, n_i . v_p); last row: n = up
  Eigen::VectorXd mu_, one_minus_mu_;          // per pixel, cosine to the sun
  Eigen::MatrixXd g_rayleigh_, g_isotropic_;   // (N + 1) x n_gamma
  Eigen::VectorXd a_overcast_;                 // (N + 1): quadrature of max(0, n.v) (1 + 2 v_y) / 3
  std::vector<double> h_, cos_sun_;            // per sample
};

}  // namespace skycal::fit
