// The start of a cloud-lighting recovery (tests/cloud_lighting_test.cc, the
// weather-inversion bench suite): the free parameters a fraction off the truth, the rest at
// it. Header-only over skycal_cloudfit, which its users link.
#pragma once
#include <algorithm>
#include <vector>

#include "skycal/cloudfit/cloud_lighting_params.h"

namespace skycal::synthetic {

// Each parameter in `free` (indices, CloudLightingNames order) times 1 +- off, the sign
// alternating over them and flipped where the bounds require; the two phase lobes both low:
// the two-lobe phase is symmetric under (g1, g2, blend) -> (g2, g1, 1 - blend), and a start
// that swapped their order would be nearer the mirrored solution. The rest at the truth.
inline cloudfit::CloudLighting LightingOffTheTruth(const cloudfit::CloudLighting& truth, const std::vector<int>& free,
                                                   double off) {
  cloudfit::CloudLighting start = truth;
  int sign = 1;
  for (int k = 0; k < cloudfit::kCloudLightingParameters; ++k) {
    if (std::find(free.begin(), free.end(), k) == free.end()) continue;
    const bool lobe = k == cloudfit::CloudLightingIndex("phase_g1") || k == cloudfit::CloudLightingIndex("phase_g2");
    const int s = lobe ? -1 : sign;
    const clouds::CloudParamSpec& spec = cloudfit::CloudLightingSpec(k);
    double v = truth[k] * (1.0 + off * s);
    if (v > spec.max || v < spec.min) v = truth[k] * (1.0 - off * s);
    start[k] = v;
    sign = -sign;
  }
  return start;
}

}  // namespace skycal::synthetic
