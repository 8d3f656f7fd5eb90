// The unseen-profile prior as a term of the fit's Ceres problem (fit_term.h): the polish after
// the linear start minimises the sky rows, the probe and the priors, and without this term it
// redrew the stripes a masked horizon's few pixels make all round, which the linear start had
// taken away (bench/results/horizon_columns.md). The residuals are the linear start's own
// (LinearSky::UnseenProfileResiduals), in log space.
#pragma once
#include <ceres/ceres.h>

#include <string>
#include <utility>
#include <vector>

#include "fit_term.h"
#include "unseen_profile.h"

namespace skycal::fit {

// Two residuals: sum_i s_i ln(sum_n a_n exp(p_n)) - sum_i s_i ln L0_i for s = second, first.
class UnseenProfileCost {
 public:
  explicit UnseenProfileCost(const UnseenProfileResidual& r) : r_(r) {}
  template <typename T>
  bool operator()(T const* const* p, T* residuals) const {
    residuals[0] = T(0.0);
    residuals[1] = T(0.0);
    size_t k = 0;
    for (int i = 0; i < 3; ++i) {
      T l(0.0);
      for (const UnseenProfileResidual::Node& n : r_.nodes[i]) l += n.a * exp(p[k++][0]);
      const T change = log(l) - r_.log_l0[i];
      residuals[0] += r_.second[i] * change;
      residuals[1] += r_.first[i] * change;
    }
    return true;
  }

 private:
  UnseenProfileResidual r_;
};

// A DynamicAutoDiffCostFunction of UnseenProfileCost, one 1-parameter block per node.
ceres::CostFunction* MakeUnseenProfileCost(const UnseenProfileResidual& r);

class UnseenProfileTerm final : public FitTerm {
 public:
  explicit UnseenProfileTerm(std::vector<UnseenProfileResidual> residuals) : residuals_(std::move(residuals)) {}
  std::string name() const override { return "unseen profile"; }
  // Only terms whose parameters the sky rows already made blocks (a column no pixel of this
  // level reaches is filled after the solve, not held by a prior alone).
  long long AddTo(ceres::Problem& problem, FitState& state, const LevelContext& level) override;

 private:
  std::vector<UnseenProfileResidual> residuals_;
};

}  // namespace skycal::fit
