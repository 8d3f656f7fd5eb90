// LinearSky's normal equations (linear_sky.h keeps Eigen out of its includers).
#pragma once
#include <Eigen/SparseCore>

#include <vector>

#include "linear_sky.h"

namespace skycal::fit {

// The normal equations N x = b of one solve: N as triplets (summed on assembly into
// `normal`) and b.
struct LinearSky::NormalSystem {
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs;
  Eigen::SparseMatrix<double> normal;
};

}  // namespace skycal::fit
