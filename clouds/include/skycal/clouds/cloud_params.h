// The cloudscape's parameters (a preset's `clouds` section) and the march's options.
//
// Every field of CloudParams has one row in CloudParameterSpecs() (name, unit, bounds,
// default, description): the JSON reader, the writer and the validator all read that
// table, as render::PresetParameterSpecs does for the sky. The lighting fields are what
// the cloud lighting fit (docs/cloud-fitting.md) tunes. Sources: Schneider 2015, "The Real-time
// Volumetric Cloudscapes of Horizon Zero Dawn" (geometry, shape, Beer-Powder, march);
// Hillaire 2016, "Physically Based Sky, Atmosphere and Cloud Rendering in Frostbite"
// (energy-conserving integration, multiple-scattering octaves after Wrenninge et al.).
#pragma once
#include <array>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace skycal::clouds {

enum class CloudIntegration {
  kEnergyConserving = 0,  // Hillaire 2016: S (1 - exp(-sigma_t dt)) / sigma_t per step (default)
  kHzdSimple = 1,         // what Horizon Zero Dawn ships: S dt per step (over-counts thick steps)
};
const char* ToString(CloudIntegration i);

struct CloudParams {
  // Geometry.
  double planet_radius_m = 6360000.0;
  double layer_bottom_m = 1500.0;
  double layer_top_m = 4000.0;
  double camera_height_m = 2.0;
  double draw_distance_m = 35000.0;
  double weather_extent_m = 60000.0;
  double base_noise_tile_m = 9000.0;
  double detail_noise_tile_m = 700.0;
  double curl_noise_tile_m = 5000.0;
  double curl_strength_m = 120.0;
  double wind_direction_deg = 0.0;  // azimuth the wind blows toward (lat-long: 0 -> +Z, 90 -> +X)
  double wind_speed_m_s = 10.0;
  // Shape.
  double coverage_scale = 1.0;
  double erosion = 0.45;
  double height_shaping = 1.0;
  double horizon_rule = 1.0;  // 0 off, 1 on
  double horizon_start_m = 15000.0;
  double horizon_end_m = 35000.0;
  double horizon_coverage = 0.5;
  // The optional 2D alto/cirrus layer (off at coverage 0).
  double cirrus_coverage = 0.0;
  double cirrus_altitude_m = 8000.0;
  double cirrus_optical_depth = 0.3;
  double cirrus_tile_m = 30000.0;
  // Lighting (the fit's parameters).
  double extinction_per_m = 0.05;
  double scattering_albedo = 0.99;
  double phase_g1 = 0.5;
  double phase_g2 = 0.9;
  double phase_blend = 0.25;
  double powder_strength = 0.4;
  double powder_view_fade = 1.0;
  double rain_absorption = 1.5;
  double ambient_strength = 1.0;
  double ambient_height_bias = 0.6;
  double ground_bounce = 1.0;
  double sun_scale = 1.0;   // the sun lighting the clouds, x the preset's sun illuminance
  double ms_octaves = 2.0;  // integer
  double ms_a = 0.5, ms_b = 0.5, ms_c = 0.5;
  double atmosphere_blend_m = 60000.0;
  double integration = 0.0;  // CloudIntegration as a number (the spec table's enum field)

  // The weather map EXR the section names (relative to the preset's directory); empty:
  // none named (the renderer's caller supplies one).
  std::string weather_map;

  CloudIntegration integration_mode() const { return static_cast<CloudIntegration>(static_cast<int>(integration)); }
};

struct CloudParamSpec {
  const char* name;
  const char* unit;
  double min, max, default_value;
  // Number kinds: a real, an integer, a switch (JSON true/false), or one of `choices`
  // (JSON string; the field holds its index).
  enum Kind { kReal, kInteger, kSwitch, kChoice } kind;
  const char* description;
  double* (*field)(CloudParams&);
  std::vector<const char*> choices = {};
};
const std::vector<CloudParamSpec>& CloudParameterSpecs();

// Where the wind has moved the clouds at `time_s` (s), m along x and z: the march samples
// camera-relative (x, z) of the weather map and the noise at (x, z) + this offset, so the
// clouds drift toward wind_direction_deg at wind_speed_m_s.
std::array<double, 2> WindOffsetM(const CloudParams& params, double time_s);

// Throws skycal::Error "origin: field 'clouds.NAME' = V is out of range (expected ... UNIT)"
// for a value outside its bounds or of the wrong kind, and for a layer whose bottom is not
// below its top, a camera above the draw distance's reach, or horizon start >= end.
void ValidateCloudParams(const CloudParams& params, const std::string& origin);

// The preset's `clouds` section (JSON object) -> parameters. Each field is
// {"value": V, ...informational unit/min/max/default/description} or a bare value; missing
// fields take their defaults; unknown keys are refused with the nearest valid name
// (core/json_schema.h). Validates. Throws skycal::Error naming origin and field.
CloudParams ParseCloudSection(const nlohmann::json& section, const std::string& origin);
// The same from the raw text render::Preset carries (render::Preset::clouds_json).
CloudParams ParseCloudSectionText(const std::string& section_json, const std::string& origin);
// Parameters -> the section (every field with unit, bounds, default and description).
nlohmann::json CloudSectionToJson(const CloudParams& params);

// The march (Schneider 2015), every optimisation switchable for measurement. Defaults:
// the game's settings.
struct MarchOptions {
  int steps_zenith = 64;      // primary samples looking straight up
  int steps_horizon = 128;    // primary samples at the horizon (linear in |view.y| between)
  int light_samples = 6;      // samples toward the sun in a cone
  // Metres between light samples. 240 m, not the 120 m of a first reading of the talk: 6 x
  // 120 m covers 720 m toward the sun, less than a cumulus is deep at a low sun, so the
  // clouds came out too bright; against a converged light integral the clouds suite measures
  // 13.2% rel RMSE at 240 m vs 30.1% at 120 m for +8% time (docs/benchmarks.md, "Clouds on lavapipe").
  double light_step_m = 240.0;
  double far_light_distance_m = 3000.0;  // the far (distant-shadow) light sample
  // Light sample i sits light_step x (i + 1) x cone_spread off the sun ray (a fixed
  // kernel of directions): HZD's cone, soft shadows from few samples. 0: on the ray, what
  // a converged light integral uses (the benchmark's reference).
  double cone_spread = 0.3;  // cone half-width per metre along the light ray, 1
  bool cheap_march = true;    // base-shape-only long steps until the base density is non-zero
  double cheap_step_factor = 2.0;  // cheap step length / full step length
  bool step_back = true;      // one cheap step back when the cheap march finds cloud
  int empty_to_cheap = 6;     // back to cheap after this many empty full samples (0: never)
  bool opacity_stop = true;   // stop once opacity >= opacity_threshold
  double opacity_threshold = 0.999;
  bool cheap_light = true;    // base-shape-only light samples once opacity > cheap_light_opacity
  double cheap_light_opacity = 0.3;
  bool far_light = true;      // the last light sample far away

  // Every optimisation off: the naive march (the benchmark's baseline).
  static MarchOptions Naive();
  // False and the field's name, value and expected range in *why (e.g. "steps_zenith = 0
  // (expected an integer in [1, 4096])").
  bool IsValid(std::string* why) const;
};

}  // namespace skycal::clouds
