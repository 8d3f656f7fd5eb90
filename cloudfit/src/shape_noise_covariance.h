// The shape noise of the cloud statistics as a full covariance (docs/cloud-fitting.md, regime 2): what
// the generalised least-squares objective of cloud_stats.h whitens with. From D draws of the
// statistics (each a render with other cloud shapes: weather maps and 3D noise textures), the
// sample covariance S is shrunk toward its own diagonal,
//   Σ = (1 - λ) S + λ diag(S),
// because D (tens) draws cannot estimate a full covariance of ~100 statistics: S is then
// singular and its small eigenvalues are noise. λ is either fixed or estimated as Schäfer &
// Strimmer ("A shrinkage approach to large-scale covariance matrix estimation", 2005, target
// "D": diagonal, unequal variances — the Ledoit–Wolf analytic optimum for that target),
//   λ* = Σ_{i≠j} Var(r_ij) / Σ_{i≠j} r_ij²   on the standardised draws,
// clamped to [0, 1]. The whitening is the fixed linear map r' = L^-1 r with Σ = L Lᵀ, so
// |r'|² = rᵀ Σ^-1 r (the GLS cost) and a least-squares solver needs nothing else.
//
// Private to skycal_cloudfit (Eigen stays out of the public headers); the unit tests include it.
#pragma once
#include <vector>

#include <Eigen/Core>

namespace skycal::cloudfit {

// Schäfer–Strimmer λ* toward the diagonal for the draws X (rows: draws, columns: variables;
// at least 2 draws). A variable with zero variance takes no part (its correlations are 0).
double DiagonalTargetShrinkage(const Eigen::MatrixXd& X);

// (1 - λ) S + λ diag(S).
Eigen::MatrixXd ShrinkTowardDiagonal(const Eigen::MatrixXd& S, double lambda);

// The sample covariance (divisor D - 1) of the draws X (rows: draws).
Eigen::MatrixXd SampleCovariance(const Eigen::MatrixXd& X);

// r' = L^-1 r for Σ = L Lᵀ (a fixed linear map: the whitened residual).
class CovarianceWhitener {
 public:
  CovarianceWhitener() = default;
  // Throws skycal::Error when Σ is not square, not finite or not positive definite.
  explicit CovarianceWhitener(const Eigen::MatrixXd& sigma);
  int size() const { return static_cast<int>(lower_.rows()); }
  bool empty() const { return lower_.size() == 0; }
  // out may alias r.
  void Apply(const double* r, double* out) const;
  const Eigen::MatrixXd& lower() const { return lower_; }

 private:
  Eigen::MatrixXd lower_;  // L, lower triangular
};

}  // namespace skycal::cloudfit
