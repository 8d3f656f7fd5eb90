#include "model_structure.h"

#include <ceres/jet.h>

namespace skycal::fit {

MiePhase MiePhaseWithDerivative(double mu, double one_minus_mu, double g) {
  using Jet1 = ceres::Jet<double, 1>;
  const NoLut none;
  StructureModel<Jet1> m(none);
  const Jet1 p = m.phase_cornette_shanks(Jet1(mu), Jet1(one_minus_mu), Jet1(g, 0));
  return {p.a, p.v[0]};
}

}  // namespace skycal::fit
