#include "skycal/cloudfit/cloud_lighting_params.h"

#include <string_view>

#include "skycal/core/error.h"

namespace skycal::cloudfit {

const std::array<const char*, kCloudLightingParameters>& CloudLightingNames() {
  static const std::array<const char*, kCloudLightingParameters> names = {
      "extinction",      "scattering_albedo", "phase_g1",         "phase_g2",         "phase_blend",
      "powder_strength", "powder_view_fade",  "rain_absorption",  "ambient_strength", "ambient_height_bias",
      "ground_bounce",   "ms_a",              "ms_b",             "ms_c",             "sun_scale"};
  return names;
}

const clouds::CloudParamSpec& CloudLightingSpec(int k) {
  static const std::array<const clouds::CloudParamSpec*, kCloudLightingParameters> rows = [] {
    std::array<const clouds::CloudParamSpec*, kCloudLightingParameters> r{};
    for (int i = 0; i < kCloudLightingParameters; ++i) {
      for (const clouds::CloudParamSpec& s : clouds::CloudParameterSpecs()) {
        if (std::string_view(s.name) == CloudLightingNames()[i]) r[i] = &s;
      }
      if (!r[i]) throw Error(std::string("cloud lighting: no clouds field named '") + CloudLightingNames()[i] + "'");
    }
    return r;
  }();
  return *rows.at(static_cast<size_t>(k));
}

int CloudLightingIndex(const std::string& name) {
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    if (name == CloudLightingNames()[k]) return k;
  }
  return -1;
}

int CloudLightingRangeEnd(int k, double value) {
  const clouds::CloudParamSpec& spec = CloudLightingSpec(k);
  const double tol = 1e-6 * (spec.max - spec.min);
  return value <= spec.min + tol ? -1 : value >= spec.max - tol ? 1 : 0;
}

CloudLighting GetCloudLighting(const clouds::CloudParams& params) {
  clouds::CloudParams p = params;  // the spec table hands out mutable pointers
  CloudLighting l{};
  for (int k = 0; k < kCloudLightingParameters; ++k) l[k] = *CloudLightingSpec(k).field(p);
  return l;
}

void SetCloudLighting(const CloudLighting& lighting, clouds::CloudParams* params) {
  for (int k = 0; k < kCloudLightingParameters; ++k) *CloudLightingSpec(k).field(*params) = lighting[k];
}

}  // namespace skycal::cloudfit
