// The data term of the sky fit: one Ceres residual block per (reference, image row,
// channel). In a lat-long every pixel of a row has the same view elevation, so the whole
// row reads the same two LUT columns: the block's parameters are, per table and column,
// the LUT entries of its channel, then g, log L_z and the reference's log exposure.
// Blocks per channel keep the Jacobian free of structural zeros.
//
// Two LUT parameterisations:
//  - free rows (several references, a day): each LUT entry u = log T is a parameter;
//  - tied rows (one reference): the image sees only (1-f) T(row0) + f T(row0+1), so the
//    two rows around the sun angle move together: T(row) = exp(u0(row) + d), one log
//    change d per (table, column, channel). This removes an exact degeneracy instead of
//    leaning on a prior, and keeps the initial preset's shape across sun angles.
//
// Residual of pixel i (natural-log radiance, solid-angle weighted, robust):
//   e_i = log(k * M_i) - log(R_i),   M_i = model radiance (shared model source),
//   r_i = sqrt(w_i) * s * sign(e_i) * sqrt(rho((e_i / s)^2)),
// so that 1/2 sum r_i^2 = 1/2 sum w_i s^2 rho((e_i/s)^2) exactly (the robust cost), with
// rho the Cauchy or Huber loss of scale s. Why log radiance: sky references span five
// orders of magnitude (twilight zenith to circumsolar), their noise is multiplicative
// (photon, exposure and compression errors scale with the signal), and an uncalibrated
// exposure becomes one additive constant; an absolute difference would be ruled by the
// brightest pixels, a plain relative one is not symmetric in over/under-estimation.
// Derivatives are analytic (the model is linear in the LUT entries; dphaseM/dg comes from
// the shared source instantiated with ceres::Jet), checked by ceres::GradientChecker.
#pragma once
#include <ceres/ceres.h>

#include <array>
#include <vector>

#include "fit_state.h"
#include "skycal/core/image.h"
#include "skycal/fit/fit_options.h"

namespace skycal::fit {

struct RowPixel {
  int x;                      // column in the level image
  double log_ref;             // log of the reference channel value
  double sqrt_weight;         // sqrt(solid angle / total fitted solid angle)
  std::array<double, 3> view; // unit view direction
  double loss_scale = 0.0;    // robust loss scale of this pixel (0: the block's loss_scale)
};

struct RowCostSetup {
  const FitState* state;               // grid, variant, overcast weight (not the fitted values)
  bool tied_rows = false;              // one log change for both rows around the sun (see above)
  const std::vector<double>* initial_log_lut = nullptr;  // u0, needed for tied rows
  std::array<double, 3> sun_dir;
  int channel;
  int level_row;                       // y in the level image
  std::vector<RowPixel> pixels;
  RobustLoss loss = RobustLoss::kCauchy;
  double loss_scale = 0.05;
  const ImageRGB* rendered = nullptr;  // Vulkan backend: the model image at the current point
  const bool* rendered_valid = nullptr;  // false: the point could not be rendered (out of domain)
};

class SkyRowCost final : public ceres::CostFunction {
 public:
  // `texel_index` receives, in parameter-block order, the index of each LUT parameter:
  // FitState::log_lut index (free rows) or FitState::DeltaIndex (tied rows); g, log L_z
  // and log exposure follow them.
  SkyRowCost(RowCostSetup setup, std::vector<size_t>* texel_index);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  int num_texels() const { return static_cast<int>(texels_.size()); }
  // Evaluate with the CPU model only (ignores `rendered`): numeric-difference baseline.
  bool EvaluateCpu(double const* const* parameters, double* residuals) const;

 private:
  // One LUT parameter: a table and column, and the 1 or 2 rows it sets. Row value =
  // exp(parameter + offset[r]) (offset 0 for free rows, u0(row) for tied rows).
  struct Texel {
    int table, dcol;
    double wcol;            // bilinear column weight
    int nrows;
    int drow[2];            // offset from row0
    double wrow[2];         // bilinear row weight
    double offset[2];
  };
  bool EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians, bool use_rendered) const;
  RowCostSetup s_;
  int row0_ = 0, col0_ = 0;
  std::vector<Texel> texels_;
  std::vector<double> mu_, one_minus_mu_, phase_r_;
  double overcast_shape_ = 0.0;  // (1 + 2 sin(elevation)) / 3 of this row
};

}  // namespace skycal::fit
