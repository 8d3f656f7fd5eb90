// The cloud lighting parameters the fit tunes: the Lighting fields of a preset's `clouds`
// section (skycal/clouds/cloud_params.h's spec table supplies each one's unit, bounds and
// description), in one fixed order shared by the Ceres parameter block, the Jet
// instantiation of the march and fit.json.
#pragma once
#include <array>
#include <string>

#include "skycal/clouds/cloud_params.h"

namespace skycal::cloudfit {

inline constexpr int kCloudLightingParameters = 15;
using CloudLighting = std::array<double, kCloudLightingParameters>;

// Spec-table names, in block order: extinction, scattering_albedo, phase_g1, phase_g2,
// phase_blend, powder_strength, powder_view_fade, rain_absorption, ambient_strength,
// ambient_height_bias, ground_bounce, ms_a, ms_b, ms_c, sun_scale.
const std::array<const char*, kCloudLightingParameters>& CloudLightingNames();
// The spec row of parameter k (unit, bounds, description).
const clouds::CloudParamSpec& CloudLightingSpec(int k);
// Index of a parameter by its spec name; -1 when it is not a fitted lighting parameter.
int CloudLightingIndex(const std::string& name);
// Where `value` sits in parameter k's range: -1 at its minimum, +1 at its maximum (within 1e-6
// of the range: a fit that ran into a bound), 0 inside.
int CloudLightingRangeEnd(int k, double value);

CloudLighting GetCloudLighting(const clouds::CloudParams& params);
void SetCloudLighting(const CloudLighting& lighting, clouds::CloudParams* params);

}  // namespace skycal::cloudfit
