#include "shape_noise_covariance.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Cholesky>

#include "skycal/core/error.h"

namespace skycal::cloudfit {

Eigen::MatrixXd SampleCovariance(const Eigen::MatrixXd& X) {
  if (X.rows() < 2) throw Error("shape noise: a covariance needs at least 2 draws, got " + std::to_string(X.rows()));
  const Eigen::MatrixXd centred = X.rowwise() - X.colwise().mean();
  return centred.transpose() * centred / static_cast<double>(X.rows() - 1);
}

double DiagonalTargetShrinkage(const Eigen::MatrixXd& X) {
  const Eigen::Index n = X.rows(), p = X.cols();
  if (n < 2) throw Error("shape noise: shrinkage needs at least 2 draws, got " + std::to_string(n));
  if (p < 2) return 1.0;  // no off-diagonal element: the diagonal is the whole matrix
  // Standardised draws z (sample sd, divisor n - 1); a constant variable stays 0.
  Eigen::MatrixXd z = X.rowwise() - X.colwise().mean();
  for (Eigen::Index j = 0; j < p; ++j) {
    const double sd = std::sqrt(z.col(j).squaredNorm() / static_cast<double>(n - 1));
    z.col(j) = sd > 0.0 ? Eigen::VectorXd(z.col(j) / sd) : Eigen::VectorXd::Zero(n);
  }
  // w_kij = z_ki z_kj; mean_ij = (zᵀz)_ij / n; Σ_k w_kij² = ((z∘z)ᵀ(z∘z))_ij.
  const Eigen::MatrixXd mean = z.transpose() * z / static_cast<double>(n);
  const Eigen::MatrixXd z2 = z.cwiseProduct(z);
  const Eigen::MatrixXd sum_sq = z2.transpose() * z2;
  const double dn = static_cast<double>(n);
  double num = 0.0, den = 0.0;
  for (Eigen::Index i = 0; i < p; ++i)
    for (Eigen::Index j = 0; j < p; ++j) {
      if (i == j) continue;
      const double r = dn / (dn - 1.0) * mean(i, j);  // the sample correlation
      const double var_r = dn / std::pow(dn - 1.0, 3) * std::max(0.0, sum_sq(i, j) - dn * mean(i, j) * mean(i, j));
      num += var_r;
      den += r * r;
    }
  if (!(den > 0.0)) return 1.0;  // no correlation at all: the diagonal
  return std::clamp(num / den, 0.0, 1.0);
}

Eigen::MatrixXd ShrinkTowardDiagonal(const Eigen::MatrixXd& S, double lambda) {
  if (!(lambda >= 0.0 && lambda <= 1.0))
    throw Error("shape noise: shrinkage " + std::to_string(lambda) + " (expected [0, 1])");
  Eigen::MatrixXd out = (1.0 - lambda) * S;
  out.diagonal() = S.diagonal();
  return out;
}

CovarianceWhitener::CovarianceWhitener(const Eigen::MatrixXd& sigma) {
  if (sigma.rows() != sigma.cols() || sigma.rows() == 0)
    throw Error("shape noise: the covariance is " + std::to_string(sigma.rows()) + "x" + std::to_string(sigma.cols()) +
                " (expected square, non-empty)");
  if (!sigma.allFinite()) throw Error("shape noise: the covariance has a non-finite element");
  const Eigen::LLT<Eigen::MatrixXd> llt(sigma);
  if (llt.info() != Eigen::Success)
    throw Error("shape noise: the covariance is not positive definite (Cholesky failed; raise the shrinkage or the sd floor)");
  lower_ = llt.matrixL();
}

void CovarianceWhitener::Apply(const double* r, double* out) const {
  Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(r, lower_.rows());
  lower_.triangularView<Eigen::Lower>().solveInPlace(v);
  Eigen::Map<Eigen::VectorXd>(out, lower_.rows()) = v;
}

}  // namespace skycal::cloudfit
