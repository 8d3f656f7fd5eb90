// The shape prior of the shared Debevec solve (internal to skycal_capture): the curve of
// Grossberg & Nayar's Empirical Model of Response (EMoR, "Modeling the space of camera
// response functions", PAMI 2004) that best explains the brackets.
//
// Why a prior at all: brackets a constant ratio r apart leave every component of ln f^-1
// that is periodic in ln x with period ln r undetermined (Grossberg & Nayar, "What can be
// known about the radiometric response from images?", ECCV 2002): g(z) + p(g(z)) gives the
// same g(z_j) - ln k_j for every bracket. Debevec's smoothness term then picks the p that
// makes the curve straightest in the code, which is wrong wherever a real curve bends within
// one bracket step (docs/capture.md, "Why brackets a constant step apart need a prior"). The
// EMoR is a principal-component model of 201 measured camera curves (DoRF): the brackets
// choose its coefficients, and the smoothness term then pulls the curve's bending toward the
// fitted EMoR curve's instead of toward none.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "skycal/capture/emor.h"

namespace skycal::capture::detail {

// The bundled basis (DataPath), read once per process; nullptr with *why when it cannot be
// read or is malformed (the caller goes on without the prior and says so).
const EmorBasis* BundledEmorBasis(std::string* why);

struct EmorFit {
  bool usable = false;
  std::string why;                 // when !usable: what failed
  std::array<double, 6> c{};       // coefficients (the first `coefficients` fitted, the rest 0)
  std::vector<double> g;           // 256 codes: ln f^-1(z / 255), f^-1(1) = 1
  double rms_dn = 0.0;             // RMS residual of the well-exposed samples, 8-bit codes (as the Huber cost counts them)
  int residuals = 0;
  int iterations = 0;
};

// Fits f = f0 + sum c_i h_i (i < coefficients) to samples codes[p * n + j] (n brackets,
// ln_k[j] their log exposure), only codes strictly between low_code and high_code, by
// Levenberg-Marquardt in code units over c and each sample's ln E (Ceres). g_start: a
// recovered ln f^-1 per code (any constant offset), which starts each ln E. Unusable when
// the fitted curve is not strictly increasing over the codes or the solve fails.
EmorFit FitEmorToSamples(const EmorBasis& basis, const std::vector<uint8_t>& codes, size_t n,
                         const std::vector<double>& ln_k, int low_code, int high_code,
                         const std::vector<double>& g_start, int coefficients);

// The period, in ln x, of the wiggles the brackets cannot see: brackets whose steps (ln_k
// sorted, differences) are all whole multiples of one step L (within 5% of L; L fitted to
// them by least squares, so that nominal shutter speeds such as 1/15 s for 1/16 s still
// count as one step) leave every component of ln f^-1 periodic in ln x with period L
// undetermined. L is the largest such step of at least a quarter stop, starting from the
// smallest step divided by 1..8; 0 when none (the steps pin the curve's wiggles) or fewer
// than two brackets.
double UndeterminedPeriod(const std::vector<double>& ln_k);

// g_free + p(g_free(z)) with p periodic in ln x (period `period`), chosen nearest g_prior
// over the codes strictly between low_code and high_code (each weighted w[z]^2): the data
// cannot tell the result from g_free, and its undetermined part is g_prior's. Phase bins of
// 1/32 period, empty bins interpolated around the circle.
std::vector<double> AdoptPeriodicPart(const std::vector<double>& g_free, const std::vector<double>& g_prior,
                                      double period, int low_code, int high_code, const std::vector<float>& w);

}  // namespace skycal::capture::detail
