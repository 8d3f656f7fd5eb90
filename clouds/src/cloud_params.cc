#include "skycal/clouds/cloud_params.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_schema.h"
#include "skycal/core/math_constants.h"

namespace skycal::clouds {
using nlohmann::json;

std::array<double, 2> WindOffsetM(const CloudParams& p, double time_s) {
  const double az = p.wind_direction_deg * kPi / 180.0;
  return {-std::sin(az) * p.wind_speed_m_s * time_s, -std::cos(az) * p.wind_speed_m_s * time_s};
}

const char* ToString(CloudIntegration i) {
  return i == CloudIntegration::kEnergyConserving ? "energy-conserving" : "hzd-simple";
}

#define SC_CLOUD_FIELD(member) [](CloudParams& p) { return &p.member; }

// A table (one entry per parameter: unit, range, default, meaning, member), data rather
// than logic: kept whole so each parameter reads in one place, though it runs past the
// house's 80-line limit on functions.
const std::vector<CloudParamSpec>& CloudParameterSpecs() {
  using S = CloudParamSpec;
  static const std::vector<CloudParamSpec> specs = {
      // Geometry.
      {"planet_radius", "m", 1.0e5, 1.0e8, 6360000.0, S::kReal,
       "radius of the planet the layer's spherical shell surrounds (a smaller radius curves the layer below the horizon sooner)",
       SC_CLOUD_FIELD(planet_radius_m)},
      {"layer_bottom", "m", 0.0, 20000.0, 1500.0, S::kReal, "altitude of the cloud layer's base above the ground (HZD: 1,500 m)",
       SC_CLOUD_FIELD(layer_bottom_m)},
      {"layer_top", "m", 0.0, 30000.0, 4000.0, S::kReal, "altitude of the cloud layer's top (HZD: 4,000 m)",
       SC_CLOUD_FIELD(layer_top_m)},
      {"camera_height", "m", 0.0, 30000.0, 2.0, S::kReal, "camera altitude above the ground", SC_CLOUD_FIELD(camera_height_m)},
      {"draw_distance", "m", 1000.0, 200000.0, 35000.0, S::kReal, "clouds are drawn within this distance along the ray (HZD: 35 km)",
       SC_CLOUD_FIELD(draw_distance_m)},
      {"weather_extent", "m", 1000.0, 1.0e6, 60000.0, S::kReal,
       "world extent the weather map covers along x and z, centred on the camera (it tiles beyond)",
       SC_CLOUD_FIELD(weather_extent_m)},
      {"base_noise_tile", "m", 100.0, 1.0e5, 9000.0, S::kReal, "world size of one tile of the 128^3 base-shape noise",
       SC_CLOUD_FIELD(base_noise_tile_m)},
      {"detail_noise_tile", "m", 10.0, 1.0e4, 700.0, S::kReal, "world size of one tile of the 32^3 detail-erosion noise",
       SC_CLOUD_FIELD(detail_noise_tile_m)},
      {"curl_noise_tile", "m", 100.0, 1.0e5, 5000.0, S::kReal, "world size of one tile of the 128^2 curl noise",
       SC_CLOUD_FIELD(curl_noise_tile_m)},
      {"curl_strength", "m", 0.0, 2000.0, 120.0, S::kReal,
       "displacement of the detail noise by the curl noise at the layer's base (fading to 0 at the top): turbulence",
       SC_CLOUD_FIELD(curl_strength_m)},
      {"wind_direction", "deg", -360.0, 360.0, 0.0, S::kReal, "azimuth the wind blows toward (lat-long: 0 -> +Z, 90 -> +X)",
       SC_CLOUD_FIELD(wind_direction_deg)},
      {"wind_speed", "m/s", 0.0, 100.0, 10.0, S::kReal, "wind speed; the clouds move by speed x --cloud-time",
       SC_CLOUD_FIELD(wind_speed_m_s)},
      // Shape.
      {"coverage_scale", "1", 0.0, 2.0, 1.0, S::kReal, "multiplies the coverage after precipitation and the horizon rule (clamped to 1; 0: no clouds)",
       SC_CLOUD_FIELD(coverage_scale)},
      {"erosion", "1", 0.0, 0.9, 0.45, S::kReal, "strength of the detail noise's erosion of the base shape's edges",
       SC_CLOUD_FIELD(erosion)},
      {"height_shaping", "1", 0.0, 1.0, 1.0, S::kReal,
       "1: HZD's height gradients by cloud type and thinner bottoms; 0: density uniform through the layer (a slab)",
       SC_CLOUD_FIELD(height_shaping)},
      {"horizon_rule", "", 0.0, 1.0, 1.0, S::kSwitch,
       "HZD's horizon rule: beyond horizon_start bias toward cumulus at horizon_coverage (nothing beyond the draw distance)",
       SC_CLOUD_FIELD(horizon_rule)},
      {"horizon_start", "m", 0.0, 200000.0, 15000.0, S::kReal, "distance where the horizon rule's bias begins (HZD: 15 km)",
       SC_CLOUD_FIELD(horizon_start_m)},
      {"horizon_end", "m", 0.0, 200000.0, 35000.0, S::kReal, "distance where the horizon rule's bias is complete (HZD: 35 km)",
       SC_CLOUD_FIELD(horizon_end_m)},
      {"horizon_coverage", "1", 0.0, 1.0, 0.5, S::kReal, "coverage the horizon rule tends to (HZD: ~50%)",
       SC_CLOUD_FIELD(horizon_coverage)},
      // The 2D alto/cirrus layer.
      {"cirrus_coverage", "1", 0.0, 1.0, 0.0, S::kReal,
       "coverage of the optional 2D alto/cirrus layer (a thin scrolling sheet above the volumetric layer); 0: off",
       SC_CLOUD_FIELD(cirrus_coverage)},
      {"cirrus_altitude", "m", 4000.0, 20000.0, 8000.0, S::kReal, "altitude of the alto/cirrus sheet (above layer_top)",
       SC_CLOUD_FIELD(cirrus_altitude_m)},
      {"cirrus_optical_depth", "1", 0.0, 5.0, 0.3, S::kReal, "vertical optical depth of the sheet where its pattern is full",
       SC_CLOUD_FIELD(cirrus_optical_depth)},
      {"cirrus_tile", "m", 1000.0, 1.0e6, 30000.0, S::kReal,
       "world size of one tile of the sheet's pattern (the base noise's Perlin-Worley x Worley, one slice)",
       SC_CLOUD_FIELD(cirrus_tile_m)},
      // Lighting.
      {"extinction", "1/m", 0.0, 1.0, 0.05, S::kReal, "extinction coefficient per unit density (Beer's law)",
       SC_CLOUD_FIELD(extinction_per_m)},
      {"scattering_albedo", "1", 0.0, 1.0, 0.99, S::kReal, "scattering / extinction of cloud droplets (before rain absorption)",
       SC_CLOUD_FIELD(scattering_albedo)},
      {"phase_g1", "1", -0.99, 0.99, 0.5, S::kReal, "Henyey-Greenstein asymmetry of the forward lobe",
       SC_CLOUD_FIELD(phase_g1)},
      {"phase_g2", "1", -0.99, 0.99, 0.9, S::kReal, "Henyey-Greenstein asymmetry of the silver-lining lobe",
       SC_CLOUD_FIELD(phase_g2)},
      {"phase_blend", "1", 0.0, 1.0, 0.25, S::kReal, "weight of the g2 lobe: phase = mix(HG(g1), HG(g2), blend)",
       SC_CLOUD_FIELD(phase_blend)},
      {"powder_strength", "1", 0.0, 1.0, 0.4, S::kReal,
       "blend of Beer's law toward Beer-Powder 2 exp(-d) (1 - exp(-2d)) for the sun light (dark edges)",
       SC_CLOUD_FIELD(powder_strength)},
      {"powder_view_fade", "1", 0.0, 1.0, 1.0, S::kReal,
       "how much the powder fades looking toward the sun: strength x mix(1, (1 - cos(view, sun)) / 2, fade)",
       SC_CLOUD_FIELD(powder_view_fade)},
      {"rain_absorption", "1", 0.0, 10.0, 1.5, S::kReal,
       "extra absorption per unit precipitation, relative to the extinction (rain clouds are darker)",
       SC_CLOUD_FIELD(rain_absorption)},
      {"ambient_strength", "1", 0.0, 10.0, 1.0, S::kReal, "scale of the ambient light from the clear sky's SH-9",
       SC_CLOUD_FIELD(ambient_strength)},
      {"ambient_height_bias", "1", 0.0, 1.0, 0.6, S::kReal,
       "ambient rises with height in the layer: 1 - bias at the base, 1 at the top", SC_CLOUD_FIELD(ambient_height_bias)},
      {"ground_bounce", "1", 0.0, 10.0, 1.0, S::kReal, "scale of the light from the lit ground below (strongest at the base)",
       SC_CLOUD_FIELD(ground_bounce)},
      {"sun_scale", "1", 0.05, 20.0, 1.0, S::kReal,
       "the sun lighting the clouds (and the ground they see), x the preset's sun illuminance: a calibration's sky "
       "fit does not pin the sun apart from the exposure",
       SC_CLOUD_FIELD(sun_scale)},
      {"ms_octaves", "1", 0.0, 4.0, 2.0, S::kInteger,
       "extra multiple-scattering octaves (Wrenninge et al., as Frostbite 2016); 0: single scattering",
       SC_CLOUD_FIELD(ms_octaves)},
      {"ms_a", "1", 0.0, 1.0, 0.5, S::kReal, "multiple scattering: extinction factor per octave", SC_CLOUD_FIELD(ms_a)},
      {"ms_b", "1", 0.0, 1.0, 0.5, S::kReal, "multiple scattering: scattering factor per octave", SC_CLOUD_FIELD(ms_b)},
      {"ms_c", "1", 0.0, 1.0, 0.5, S::kReal, "multiple scattering: phase-asymmetry factor per octave", SC_CLOUD_FIELD(ms_c)},
      {"atmosphere_blend", "m", 1000.0, 1.0e7, 60000.0, S::kReal,
       "e-folding distance of the clouds' blend toward the atmosphere's colour", SC_CLOUD_FIELD(atmosphere_blend_m)},
      {"integration", "", 0.0, 1.0, 0.0, S::kChoice,
       "per-step integration: energy-conserving (Hillaire 2016) or hzd-simple (what Horizon Zero Dawn runs)",
       SC_CLOUD_FIELD(integration), {"energy-conserving", "hzd-simple"}},
  };
  return specs;
}
#undef SC_CLOUD_FIELD

namespace {

std::string Expected(const CloudParamSpec& s) {
  if (s.kind == CloudParamSpec::kSwitch) return "true or false";
  if (s.kind == CloudParamSpec::kChoice) {
    std::string e;
    for (const char* c : s.choices) e += (e.empty() ? "\"" : " or \"") + std::string(c) + "\"";
    return e;
  }
  const std::string what = s.kind == CloudParamSpec::kInteger ? "an integer" : "a finite value";
  return what + " in [" + FormatNumber(s.min) + ", " + FormatNumber(s.max) + "]" + (*s.unit ? std::string(" ") + s.unit : "");
}

std::string Field(const std::string& origin, const std::string& name) { return JsonField(origin, "clouds." + name); }

}  // namespace

void ValidateCloudParams(const CloudParams& in, const std::string& origin) {
  CloudParams p = in;  // the specs hand out mutable pointers
  for (const CloudParamSpec& s : CloudParameterSpecs()) {
    const double v = *s.field(p);
    const bool integral = s.kind != CloudParamSpec::kReal;
    if (!std::isfinite(v) || v < s.min || v > s.max || (integral && v != std::floor(v))) {
      throw Error(Field(origin, s.name) + " = " + FormatNumber(v) + " is out of range (expected " + Expected(s) + ")");
    }
  }
  if (!(p.layer_bottom_m < p.layer_top_m)) {
    throw Error(Field(origin, "layer_bottom") + " = " + FormatNumber(p.layer_bottom_m) + " m is not below clouds.layer_top = " +
                FormatNumber(p.layer_top_m) + " m (expected bottom < top)");
  }
  if (p.cirrus_coverage > 0.0 && !(p.cirrus_altitude_m > p.layer_top_m && p.cirrus_altitude_m > p.camera_height_m)) {
    throw Error(Field(origin, "cirrus_altitude") + " = " + FormatNumber(p.cirrus_altitude_m) +
                " m is not above clouds.layer_top and the camera (expected a sheet above both)");
  }
  if (!(p.horizon_start_m < p.horizon_end_m)) {
    throw Error(Field(origin, "horizon_start") + " = " + FormatNumber(p.horizon_start_m) +
                " m is not below clouds.horizon_end = " + FormatNumber(p.horizon_end_m) + " m");
  }
}

CloudParams ParseCloudSection(const json& section, const std::string& origin) {
  if (!section.is_object()) throw Error(JsonField(origin, "clouds") + ": expected an object, got " + section.dump());
  std::vector<std::string> names{"weather_map"};
  for (const CloudParamSpec& s : CloudParameterSpecs()) names.push_back(s.name);
  RequireKnownKeys(section, names, origin, "clouds.");
  CloudParams p;
  if (section.contains("weather_map")) {
    const json& w = section["weather_map"];
    if (!w.is_string() || w.get<std::string>().empty()) {
      throw Error(Field(origin, "weather_map") + ": expected an EXR file name (relative to the preset), got " + w.dump());
    }
    p.weather_map = w.get<std::string>();
  }
  for (const CloudParamSpec& s : CloudParameterSpecs()) {
    if (!section.contains(s.name)) continue;  // a partial section: the rest take their defaults
    const json* v = &section[s.name];
    if (v->is_object()) {
      RequireKnownKeys(*v, {"value", "unit", "min", "max", "default", "description"}, origin,
                       std::string("clouds.") + s.name + ".");
      if (!v->contains("value")) throw Error(Field(origin, std::string(s.name) + ".value") + " is missing");
      v = &(*v)["value"];
    }
    double* out = s.field(p);
    const std::string bad = Field(origin, s.name) + ": expected " + Expected(s) + ", got " + v->dump();
    switch (s.kind) {
      case CloudParamSpec::kSwitch:
        if (!v->is_boolean()) throw Error(bad);
        *out = v->get<bool>() ? 1.0 : 0.0;
        break;
      case CloudParamSpec::kChoice: {
        if (!v->is_string()) throw Error(bad);
        const std::string text = v->get<std::string>();
        bool found = false;
        for (size_t i = 0; i < s.choices.size(); ++i) {
          if (text == s.choices[i]) {
            *out = static_cast<double>(i);
            found = true;
          }
        }
        if (!found) throw Error(bad);
        break;
      }
      default:
        if (!v->is_number()) throw Error(bad);
        *out = v->get<double>();
    }
  }
  ValidateCloudParams(p, origin);
  return p;
}

CloudParams ParseCloudSectionText(const std::string& text, const std::string& origin) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw Error(JsonField(origin, "clouds") + ": not valid JSON (" + e.what() + ")");
  }
  return ParseCloudSection(j, origin);
}

json CloudSectionToJson(const CloudParams& in) {
  CloudParams p = in;
  json j = json::object();
  if (!p.weather_map.empty()) j["weather_map"] = p.weather_map;
  for (const CloudParamSpec& s : CloudParameterSpecs()) {
    const double v = *s.field(p);
    json value;
    json def;
    switch (s.kind) {
      case CloudParamSpec::kSwitch:
        value = v != 0.0;
        def = s.default_value != 0.0;
        break;
      case CloudParamSpec::kChoice:
        value = s.choices.at(static_cast<size_t>(v));
        def = s.choices.at(static_cast<size_t>(s.default_value));
        break;
      case CloudParamSpec::kInteger:
        value = static_cast<long long>(v);
        def = static_cast<long long>(s.default_value);
        break;
      default:
        value = v;
        def = s.default_value;
    }
    json entry = {{"value", value}, {"unit", s.unit}, {"default", def}, {"description", s.description}};
    if (s.kind == CloudParamSpec::kReal || s.kind == CloudParamSpec::kInteger) {
      entry["min"] = s.min;
      entry["max"] = s.max;
    }
    j[s.name] = entry;
  }
  return j;
}

MarchOptions MarchOptions::Naive() {
  MarchOptions m;
  m.cheap_march = false;
  m.step_back = false;
  m.empty_to_cheap = 0;
  m.opacity_stop = false;
  m.cheap_light = false;
  m.far_light = false;
  return m;
}

bool MarchOptions::IsValid(std::string* why) const {
  auto count = [&](const char* name, int v, int lo, int hi) {
    if (v >= lo && v <= hi) return true;
    *why = std::string(name) + " = " + std::to_string(v) + " (expected an integer in [" + std::to_string(lo) + ", " +
           std::to_string(hi) + "])";
    return false;
  };
  auto real = [&](const char* name, double v, double lo, double hi, const char* unit) {
    if (std::isfinite(v) && v >= lo && v <= hi) return true;
    *why = std::string(name) + " = " + FormatNumber(v) + " (expected a value in [" + FormatNumber(lo) + ", " +
           FormatNumber(hi) + "] " + unit + ")";
    return false;
  };
  return count("steps_zenith", steps_zenith, 1, 4096) && count("steps_horizon", steps_horizon, 1, 4096) &&
         count("light_samples", light_samples, 0, 64) && count("empty_to_cheap", empty_to_cheap, 0, 4096) &&
         real("light_step", light_step_m, 1.0, 1.0e4, "m") && real("far_light_distance", far_light_distance_m, 1.0, 1.0e5, "m") &&
         real("cone_spread", cone_spread, 0.0, 1.0, "(m per m along the light ray)") &&
         real("cheap_step_factor", cheap_step_factor, 1.0, 16.0, "(x the full step)") &&
         real("opacity_threshold", opacity_threshold, 0.5, 1.0, "(1)") &&
         real("cheap_light_opacity", cheap_light_opacity, 0.0, 1.0, "(1)");
}

}  // namespace skycal::clouds
