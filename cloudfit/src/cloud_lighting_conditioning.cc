#include "cloud_lighting_conditioning.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"

namespace skycal::cloudfit {
namespace {

constexpr int kP = kCloudLightingParameters;

// sigma x sqrt(diag((J^T J)^-1)) over the columns `cols` of J, through the SVD (stable where
// J^T J is near singular: a tiny singular value gives a huge, not a NaN, error).
std::vector<double> PredictedErrors(const Eigen::MatrixXd& j, const std::vector<int>& cols, double sigma,
                                    std::vector<double>* singular_values) {
  Eigen::MatrixXd sub(j.rows(), static_cast<Eigen::Index>(cols.size()));
  for (size_t c = 0; c < cols.size(); ++c) sub.col(static_cast<Eigen::Index>(c)) = j.col(cols[c]);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(sub, Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  const Eigen::MatrixXd& v = svd.matrixV();
  std::vector<double> err(cols.size(), 0.0);
  for (size_t c = 0; c < cols.size(); ++c) {
    double var = 0.0;
    for (Eigen::Index k = 0; k < s.size(); ++k) {
      var += s[k] > 0.0 ? v(static_cast<Eigen::Index>(c), k) * v(static_cast<Eigen::Index>(c), k) / (s[k] * s[k])
                        : std::numeric_limits<double>::infinity();
    }
    err[c] = sigma * std::sqrt(var);
  }
  if (singular_values) {
    // Of the column-normalised matrix: scale-free, comparable across parameters.
    Eigen::MatrixXd n = sub;
    for (Eigen::Index c = 0; c < n.cols(); ++c) n.col(c) /= std::max(n.col(c).norm(), 1e-300);
    const Eigen::VectorXd sn = Eigen::JacobiSVD<Eigen::MatrixXd>(n).singularValues();
    singular_values->assign(sn.data(), sn.data() + sn.size());
  }
  return err;
}

}  // namespace

Conditioning AnalyseConditioning(const std::vector<double>& jacobian, const CloudLighting& theta,
                                 const ConditioningOptions& o) {
  if (jacobian.empty() || jacobian.size() % kP != 0) throw Error("cloud lighting conditioning: empty Jacobian");
  if (!o.user_held.empty() && o.user_held.size() != static_cast<size_t>(kP)) {
    throw Error("cloud lighting conditioning: held flags of the wrong size");
  }
  const Eigen::Index rows = static_cast<Eigen::Index>(jacobian.size() / kP);
  Conditioning out;
  out.parameters.resize(kP);
  Eigen::MatrixXd j(rows, kP);
  for (int k = 0; k < kP; ++k) {
    const clouds::CloudParamSpec& spec = CloudLightingSpec(k);
    ParameterConditioning& pc = out.parameters[k];
    pc.scale = std::max(std::abs(theta[k]), 0.01 * (spec.max - spec.min));
    for (Eigen::Index r = 0; r < rows; ++r) j(r, k) = jacobian[static_cast<size_t>(r) * kP + k] * pc.scale;
    pc.sensitivity = j.col(k).norm() / std::sqrt(static_cast<double>(rows));
  }
  // Pairwise collinearity (|cos| between columns).
  for (int a = 0; a < kP; ++a) {
    for (int b = 0; b < kP; ++b) {
      const double na = j.col(a).norm(), nb = j.col(b).norm();
      if (a == b || na <= 0.0 || nb <= 0.0) continue;
      const double c = std::abs(j.col(a).dot(j.col(b))) / (na * nb);
      if (c > out.parameters[a].collinear_cosine) {
        out.parameters[a].collinear_cosine = c;
        out.parameters[a].most_collinear = b;
      }
    }
  }
  std::vector<int> observed, free;
  for (int k = 0; k < kP; ++k) {
    ParameterConditioning& pc = out.parameters[k];
    if (pc.sensitivity < o.min_sensitivity) {
      pc.held = true;
      pc.predicted_relative_error = std::numeric_limits<double>::infinity();
      pc.why = "unobserved: the cloud pixels do not depend on it (RMS d log L / d log theta = " +
               FormatNumber(pc.sensitivity) + " < " + FormatNumber(o.min_sensitivity) + ")";
      continue;
    }
    observed.push_back(k);
    if (!o.user_held.empty() && o.user_held[k]) {
      pc.held = true;
      pc.why = k < static_cast<int>(o.held_why.size()) && !o.held_why[k].empty() ? o.held_why[k] : "held on request (--cloud-hold)";
    } else {
      free.push_back(k);
    }
  }
  if (!observed.empty()) {
    // Separability among every observed parameter: 1 / sqrt(VIF) of the normalised columns.
    const std::vector<double> e_all = PredictedErrors(j, observed, 1.0, &out.singular_values);
    for (size_t c = 0; c < observed.size(); ++c) {
      const double norm = j.col(observed[c]).norm();
      out.parameters[observed[c]].separability = std::isfinite(e_all[c]) && e_all[c] > 0.0 ? 1.0 / (e_all[c] * norm) : 0.0;
    }
  }
  while (!free.empty()) {
    const std::vector<double> e = PredictedErrors(j, free, o.noise, &out.singular_values_free);
    size_t worst = 0;
    for (size_t c = 0; c < free.size(); ++c) {
      out.parameters[free[c]].predicted_relative_error = e[c];
      if (!(e[c] <= e[worst])) worst = c;
    }
    if (!o.auto_hold || e[worst] <= o.max_relative_error) break;
    ParameterConditioning& pc = out.parameters[free[worst]];
    pc.held = true;
    pc.inseparable = true;
    const std::string partner = pc.most_collinear >= 0 ? CloudLightingNames()[pc.most_collinear] : "none";
    pc.why = "inseparable: predicted error " + FormatNumber(100.0 * e[worst]) + "% at " + FormatNumber(100.0 * o.noise) +
             "% pixel noise (> " + FormatNumber(100.0 * o.max_relative_error) + "%) with the others free; most collinear with " +
             partner + " (|cos| " + FormatNumber(pc.collinear_cosine) + ")";
    free.erase(free.begin() + static_cast<long>(worst));
  }
  if (free.empty()) out.singular_values_free.clear();
  return out;
}

}  // namespace skycal::cloudfit
