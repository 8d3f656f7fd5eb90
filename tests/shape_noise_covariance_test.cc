// The full generalised least-squares whitening of the cloud statistics (cloudfit/src/
// shape_noise_covariance.h): the whitened residual's squared norm is rᵀ Σ^-1 r, the shrinkage
// toward the diagonal, and controls that show each check can fail.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "shape_noise_covariance.h"
#include "skycal/core/error.h"

namespace skycal::cloudfit {
namespace {

// A correlated 5x5 covariance: A Aᵀ + diag (positive definite), correlations up to ~0.9.
Eigen::MatrixXd Correlated() {
  Eigen::MatrixXd A(5, 2);
  A << 1.0, 0.2, 0.9, 0.3, 0.8, -0.4, 0.1, 1.1, -0.5, 0.7;
  Eigen::MatrixXd S = A * A.transpose();
  S.diagonal() += Eigen::VectorXd::Constant(5, 0.15);
  return S;
}

TEST(ShapeNoiseCovariance, WhitenedNormIsTheGlsCost) {
  const Eigen::MatrixXd sigma = Correlated();
  const CovarianceWhitener w(sigma);
  ASSERT_EQ(w.size(), 5);
  Eigen::VectorXd r(5);
  r << 0.3, -0.1, 0.25, 0.4, -0.2;
  Eigen::VectorXd out(5);
  w.Apply(r.data(), out.data());
  // rᵀ Σ^-1 r by another route (LDLᵀ solve, not the Cholesky factor Apply uses).
  const double gls = r.dot(sigma.ldlt().solve(r));
  EXPECT_NEAR(out.squaredNorm(), gls, 1e-12 * gls);
  // L^-1 Σ L^-ᵀ = I: each whitened column of Σ's factor is a unit vector.
  Eigen::MatrixXd white(5, 5);
  for (int j = 0; j < 5; ++j) {
    Eigen::VectorXd col = w.lower().col(j), wc(5);
    w.Apply(col.data(), wc.data());
    white.col(j) = wc;
  }
  EXPECT_LT((white - Eigen::MatrixXd::Identity(5, 5)).cwiseAbs().maxCoeff(), 1e-12);
  // In place (out aliases r) gives the same.
  Eigen::VectorXd in_place = r;
  w.Apply(in_place.data(), in_place.data());
  EXPECT_LT((in_place - out).cwiseAbs().maxCoeff(), 1e-15);
  // Control: the diagonal whitening (r_k / sd_k) of the same residual is not the GLS cost
  // when the statistics correlate (here it differs by more than 20%): the identity above is
  // not vacuous.
  const double diag = r.cwiseQuotient(sigma.diagonal().cwiseSqrt()).squaredNorm();
  EXPECT_GT(std::abs(diag - gls), 0.2 * gls) << "diagonal " << diag << " vs GLS " << gls;
  // A diagonal Σ: full and diagonal whitening agree (the full GLS generalises the diagonal one).
  const Eigen::MatrixXd d = sigma.diagonal().asDiagonal();
  const CovarianceWhitener wd(d);
  wd.Apply(r.data(), out.data());
  EXPECT_NEAR(out.squaredNorm(), diag, 1e-12 * diag);
}

TEST(ShapeNoiseCovariance, SingularOrBadCovarianceIsRefused) {
  Eigen::MatrixXd s = Eigen::MatrixXd::Ones(3, 3);  // rank 1
  EXPECT_THROW(CovarianceWhitener{s}, Error);
  EXPECT_THROW(CovarianceWhitener{Eigen::MatrixXd(2, 3)}, Error);
  s = Eigen::MatrixXd::Identity(3, 3);
  s(1, 1) = std::nan("");
  EXPECT_THROW(CovarianceWhitener{s}, Error);
  // Shrinking a singular sample covariance toward its diagonal makes it positive definite.
  EXPECT_NO_THROW(CovarianceWhitener{ShrinkTowardDiagonal(Eigen::MatrixXd::Ones(3, 3), 0.1)});
  EXPECT_THROW(ShrinkTowardDiagonal(Eigen::MatrixXd::Ones(3, 3), 1.5), Error);
}

TEST(ShapeNoiseCovariance, ShrinkageKeepsTheDiagonalAndScalesCorrelations) {
  const Eigen::MatrixXd S = Correlated();
  const Eigen::MatrixXd half = ShrinkTowardDiagonal(S, 0.5);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) EXPECT_NEAR(half(i, j), i == j ? S(i, i) : 0.5 * S(i, j), 1e-15);
  const Eigen::MatrixXd diag = ShrinkTowardDiagonal(S, 1.0);
  EXPECT_EQ((diag - Eigen::MatrixXd(S.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), 0.0);
}

// Draws of p variables: independent (the diagonal is the truth: λ* should be near 1), or one
// common factor with loading 0.9 (correlations ~0.8, well determined by 40 draws: λ* small).
Eigen::MatrixXd Draws(int n, int p, double loading, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd X(n, p);
  for (int k = 0; k < n; ++k) {
    const double f = g(rng);
    for (int j = 0; j < p; ++j) X(k, j) = (1.0 + j) * (loading * f + std::sqrt(1.0 - loading * loading) * g(rng));
  }
  return X;
}

TEST(ShapeNoiseCovariance, EstimatedShrinkageFollowsTheCorrelations) {
  // Schäfer & Strimmer's λ* = Σ Var(r_ij) / Σ r_ij²: independent variables have sample
  // correlations that are all noise (E r² ≈ Var r ≈ 1/n), so λ* ≈ 1 (measured 1.0, clamped);
  // a strong common factor has r² ≈ 0.66 ≫ Var r, so λ* ≈ 0 (measured 0.078).
  const double independent = DiagonalTargetShrinkage(Draws(40, 20, 0.0, 7));
  const double factor = DiagonalTargetShrinkage(Draws(40, 20, 0.9, 7));
  std::cout << "[shape noise] lambda independent " << independent << ", common factor " << factor << "\n";
  EXPECT_GT(independent, 0.7);
  EXPECT_LT(factor, 0.2);
  // The estimate does not depend on the variables' scales (it works on correlations).
  Eigen::MatrixXd X = Draws(40, 20, 0.9, 7);
  const double before = DiagonalTargetShrinkage(X);
  X.col(3) *= 1000.0;
  EXPECT_NEAR(DiagonalTargetShrinkage(X), before, 1e-12);
  // Sample covariance: divisor n - 1 (two draws ±1 of one variable: variance 2).
  Eigen::MatrixXd two(2, 1);
  two << 1.0, -1.0;
  EXPECT_NEAR(SampleCovariance(two)(0, 0), 2.0, 1e-15);
  EXPECT_THROW(SampleCovariance(Eigen::MatrixXd(1, 3)), Error);
}

}  // namespace
}  // namespace skycal::cloudfit
