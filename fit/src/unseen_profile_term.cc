#include "unseen_profile_term.h"

namespace skycal::fit {

ceres::CostFunction* MakeUnseenProfileCost(const UnseenProfileResidual& r) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<UnseenProfileCost, 4>(new UnseenProfileCost(r));
  for (const auto& column : r.nodes)
    for (size_t n = 0; n < column.size(); ++n) cost->AddParameterBlock(1);
  cost->SetNumResiduals(2);
  return cost;
}

long long UnseenProfileTerm::AddTo(ceres::Problem& problem, FitState& /*state*/, const LevelContext& /*level*/) {
  long long residuals = 0;
  for (const UnseenProfileResidual& r : residuals_) {
    std::vector<double*> blocks;
    bool in_problem = true;
    for (const auto& column : r.nodes)
      for (const UnseenProfileResidual::Node& n : column) {
        blocks.push_back(n.parameter);
        in_problem = in_problem && problem.HasParameterBlock(n.parameter);
      }
    if (!in_problem) continue;
    problem.AddResidualBlock(MakeUnseenProfileCost(r), nullptr, blocks);
    residuals += 2;
  }
  return residuals;
}

}  // namespace skycal::fit
