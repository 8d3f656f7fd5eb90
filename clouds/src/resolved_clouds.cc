#include "resolved_clouds.h"

#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/renderer.h"

namespace skycal::clouds {
namespace {
// The clear sky is rendered this small for its SH-9 (order 2 resolves nothing finer than
// ~60 deg; 128 x 64 pixels put the quadrature error far below that).
constexpr int kShWidth = 128, kShHeight = 64;

static_assert(CloudModelD::CLOUD_BASE_SIZE == CloudNoise::kBaseSize && CloudModelD::CLOUD_DETAIL_SIZE == CloudNoise::kDetailSize &&
                  CloudModelD::CLOUD_CURL_SIZE == CloudNoise::kCurlSize,
              "clouds/model/cloud_textures.glsl.h sizes must match cloud_textures.h");
}  // namespace

bool CloudRenderRequest::IsValid(std::string* why) const {
  render::RenderRequest r;
  r.width = width;
  r.height = height;
  r.sun_dir = sun_dir;
  if (!r.IsValid(why)) return false;
  if (!std::isfinite(time_s) || std::abs(time_s) > 1.0e7) {
    *why = "cloud time " + std::to_string(time_s) + " s (expected a finite time within 1e7 s)";
    return false;
  }
  if (!march.IsValid(why)) {
    *why = "march: " + *why;
    return false;
  }
  return true;
}

namespace {
// Throws naming `origin` and `what` unless v holds n values.
void CheckSize(const std::vector<float>& v, size_t n, const std::string& origin, const std::string& what) {
  if (v.size() != n) {
    throw Error(origin + ": " + what + " has " + std::to_string(v.size()) + " values, expected " + std::to_string(n));
  }
}
// ... and each value finite and in [lo, hi].
void CheckValues(const std::vector<float>& v, size_t n, float lo, float hi, const std::string& origin,
                 const std::string& what) {
  CheckSize(v, n, origin, what);
  for (size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i]) || v[i] < lo || v[i] > hi) {
      throw Error(origin + ": " + what + " value " + std::to_string(i) + " = " + std::to_string(v[i]) +
                  " (expected finite, in [" + std::to_string(lo) + ", " + std::to_string(hi) + "])");
    }
  }
}
constexpr size_t kBaseValues = size_t{CloudNoise::kBaseSize} * CloudNoise::kBaseSize * CloudNoise::kBaseSize * 4;
constexpr size_t kDetailValues = size_t{CloudNoise::kDetailSize} * CloudNoise::kDetailSize * CloudNoise::kDetailSize * 3;
constexpr size_t kCurlValues = size_t{CloudNoise::kCurlSize} * CloudNoise::kCurlSize * 3;

}  // namespace

void ValidateCloudNoise(const CloudNoise& noise, const std::string& origin) {
  CheckValues(noise.base, kBaseValues, 0.0f, 1.0f, origin, "base noise");
  CheckValues(noise.detail, kDetailValues, 0.0f, 1.0f, origin, "detail noise");
  CheckValues(noise.curl, kCurlValues, -1.0f, 1.0f, origin, "curl noise");
}

void ValidateCloudTextures(const CloudNoise& noise, const WeatherMap& weather, const std::string& origin) {
  // Noise that carries its checksum was validated where it was made (GenerateCloudNoise,
  // LoadOrGenerateCloudNoise): 8.7 M values, ~4% of a 512x256 render to re-check. Here
  // only its sizes, which every read's indexing relies on; noise made by hand (no
  // checksum) is checked in full.
  if (noise.sha256.empty()) {
    ValidateCloudNoise(noise, origin);
  } else {
    CheckSize(noise.base, kBaseValues, origin, "base noise");
    CheckSize(noise.detail, kDetailValues, origin, "detail noise");
    CheckSize(noise.curl, kCurlValues, origin, "curl noise");
  }
  // Powers of two: the shared source wraps texel indices with a mask (cloud_textures.glsl.h).
  auto power_of_two = [](int n) { return n > 0 && (n & (n - 1)) == 0; };
  if (!power_of_two(weather.width) || !power_of_two(weather.height) || weather.width > 16384 || weather.height > 16384) {
    throw Error(origin + ": weather map is " + std::to_string(weather.width) + "x" + std::to_string(weather.height) +
                " texels (expected a power of two from 1 to 16384 a side)");
  }
  // The weather map is small (a 512^2 map is 0.8 M values) and callers build their own
  // (the fit, procedural maps): checked every render.
  CheckValues(weather.rgb, static_cast<size_t>(weather.width) * weather.height * 3, 0.0f, 1.0f, origin,
              "weather map (R coverage, G precipitation, B type)");
}

namespace {

// The cloud parameters into the shared model's uniforms (lengths in m; the wind offset in
// m at time_s).
void ShadeFromParams(const CloudParams& c, double time_s, CloudShadeD& s) {
  s.planet_radius = c.planet_radius_m;
  s.layer_bottom = c.layer_bottom_m;
  s.layer_top = c.layer_top_m;
  s.camera_height = c.camera_height_m;
  s.draw_distance = c.draw_distance_m;
  s.weather_extent = c.weather_extent_m;
  s.base_tile = c.base_noise_tile_m;
  s.detail_tile = c.detail_noise_tile_m;
  s.curl_tile = c.curl_noise_tile_m;
  s.curl_strength = c.curl_strength_m;
  // Density at x is the texture at x - wind x time: the clouds drift with the wind.
  const std::array<double, 2> wind = WindOffsetM(c, time_s);
  s.wind_x = wind[0];
  s.wind_z = wind[1];
  s.coverage_scale = c.coverage_scale;
  s.erosion = c.erosion;
  s.height_shaping = c.height_shaping;
  s.horizon_rule = c.horizon_rule;
  s.horizon_start = c.horizon_start_m;
  s.horizon_end = c.horizon_end_m;
  s.horizon_coverage = c.horizon_coverage;
  s.cirrus_coverage = c.cirrus_coverage;
  s.cirrus_altitude = c.cirrus_altitude_m;
  s.cirrus_depth = c.cirrus_optical_depth;
  s.cirrus_tile = c.cirrus_tile_m;
  s.extinction = c.extinction_per_m;
  s.albedo = c.scattering_albedo;
  s.g1 = c.phase_g1;
  s.g2 = c.phase_g2;
  s.phase_blend = c.phase_blend;
  s.powder_strength = c.powder_strength;
  s.powder_view_fade = c.powder_view_fade;
  s.rain_absorption = c.rain_absorption;
  s.ambient_strength = c.ambient_strength;
  s.ambient_height_bias = c.ambient_height_bias;
  s.ground_bounce = c.ground_bounce;
  s.ms_a = c.ms_a;
  s.ms_b = c.ms_b;
  s.ms_c = c.ms_c;
  s.atmosphere_blend = c.atmosphere_blend_m;
}

// The clear sky's SH-9 (no disc: the sun is the direct term) and its irradiance on an
// upward face: a CPU render of the preset at kShWidth x kShHeight, the costly part of the
// light, which depends on the preset and the sun alone.
struct ClearSkyLight {
  render::ShCoefficients sh;
  render::Rgb e_up;
};
ClearSkyLight SkyLight(const render::Preset& preset, const std::array<double, 3>& sun) {
  render::RenderRequest sky_request;
  sky_request.sun_dir = sun;
  sky_request.width = kShWidth;
  sky_request.height = kShHeight;
  sky_request.sun_disc = false;
  const ImageRGB sky = render::CreateRenderer(render::Backend::kCpu)->Render(preset, sky_request);
  ClearSkyLight light;
  light.sh = render::ProjectSh9(sky);
  light.e_up = render::ShIrradiance(light.sh, {0.0, 1.0, 0.0});
  return light;
}

// The light the atmosphere already models, into s: direct sun, the clear sky's SH-9 and
// its irradiance on an upward face, the lit ground's radiance.
void ShadeFromAtmosphere(const render::Preset& preset, const std::array<double, 3>& sun, double sun_scale,
                         const ClearSkyLight& sky, CloudShadeD& s) {
  // The sun below the horizon lights the clouds by the sky's ambient alone: no direct term
  // (the LUT's rows below the horizon interpolate toward 0 but not to it; a still render
  // at dusk has no sunlit clouds rather than ones lit through the ground).
  render::Rgb e_sun = sun[1] > 0.0 ? render::SunIlluminanceAtGround(preset, sun) : render::Rgb{0.0, 0.0, 0.0};
  for (double& e : e_sun) e *= sun_scale;  // CloudParams::sun_scale: the clouds' sun (and their ground's)
  s.sun_illuminance = glsl::Vec3<double>(e_sun[0], e_sun[1], e_sun[2]);
  glsl::Vec3<double>* shs[9] = {&s.sh0, &s.sh1, &s.sh2, &s.sh3, &s.sh4, &s.sh5, &s.sh6, &s.sh7, &s.sh8};
  for (int k = 0; k < 9; ++k) *shs[k] = glsl::Vec3<double>(sky.sh[k][0], sky.sh[k][1], sky.sh[k][2]);
  const render::Rgb& e_up = sky.e_up;
  s.sky_irradiance_up = glsl::Vec3<double>(std::max(e_up[0], 0.0), std::max(e_up[1], 0.0), std::max(e_up[2], 0.0));
  const double k = preset.ground_albedo / kPi, cos_sun = std::max(sun[1], 0.0);
  s.ground_radiance = glsl::Vec3<double>(k * (e_sun[0] * cos_sun + s.sky_irradiance_up.x),
                                         k * (e_sun[1] * cos_sun + s.sky_irradiance_up.y),
                                         k * (e_sun[2] * cos_sun + s.sky_irradiance_up.z));
}

// The march's step counts, shortcuts and thresholds into s.
void ShadeFromMarch(const MarchOptions& m, CloudShadeD& s) {
  s.steps_zenith = m.steps_zenith;
  s.steps_horizon = m.steps_horizon;
  s.light_samples = m.light_samples;
  s.cheap_march = m.cheap_march ? 1 : 0;
  s.step_back = m.step_back ? 1 : 0;
  s.empty_to_cheap = m.empty_to_cheap;
  s.opacity_stop = m.opacity_stop ? 1 : 0;
  s.cheap_light = m.cheap_light ? 1 : 0;
  s.far_light = m.far_light ? 1 : 0;
  s.cheap_step_factor = m.cheap_step_factor;
  s.opacity_threshold = m.opacity_threshold;
  s.cheap_light_opacity = m.cheap_light_opacity;
  s.light_step = m.light_step_m;
  s.far_light_distance = m.far_light_distance_m;
  s.cone_spread = m.cone_spread;
}

}  // namespace

std::vector<CloudShadeD> ResolveCloudShades(const CloudScene& scene, const std::vector<const CloudParams*>& params,
                                            const CloudRenderRequest& request) {
  if (!scene.preset || !scene.noise || !scene.weather) throw Error("cloud render: incomplete scene");
  for (const CloudParams* c : params)
    if (!c) throw Error("cloud render: incomplete scene");
  std::string why;
  if (!request.IsValid(&why)) throw Error("cloud render request: " + why);
  for (const CloudParams* c : params) ValidateCloudParams(*c, "cloud parameters");
  ValidateCloudTextures(*scene.noise, *scene.weather, "cloud textures");
  const render::Preset& preset = *scene.preset;
  const auto sun = latlong::Normalized(request.sun_dir, "sun direction");
  const ClearSkyLight sky = SkyLight(preset, sun);  // once for every parameter set

  std::vector<CloudShadeD> shades;
  for (const CloudParams* c : params) {
    CloudShadeD s{};
    ShadeFromParams(*c, request.time_s, s);
    s.sun_dir = glsl::Vec3<double>(sun[0], sun[1], sun[2]);
    ShadeFromAtmosphere(preset, sun, c->sun_scale, sky, s);
    s.weather_width = scene.weather->width;
    s.weather_height = scene.weather->height;
    s.ms_octaves = static_cast<int>(c->ms_octaves);
    s.integration = static_cast<int>(c->integration);
    ShadeFromMarch(request.march, s);
    shades.push_back(s);
  }
  return shades;
}

CloudShadeD ResolveCloudShade(const CloudScene& scene, const CloudRenderRequest& request) {
  return ResolveCloudShades(scene, {scene.params}, request).front();
}

std::vector<float> PackCloudShade(const CloudShadeD& d) {
  std::vector<float> v;
#define SC_FIELD(name) v.push_back(static_cast<float>(d.name));
#define SC_FIELD_VEC3(name)                  \
  v.push_back(static_cast<float>(d.name.x)); \
  v.push_back(static_cast<float>(d.name.y)); \
  v.push_back(static_cast<float>(d.name.z));
#define SC_FIELD_INT(name) v.push_back(static_cast<float>(d.name));
#include "../model/cloud_shade_fields.glsl.h"
#undef SC_FIELD
#undef SC_FIELD_VEC3
#undef SC_FIELD_INT
  return v;
}

LatLongTrig MakeLatLongTrig(int width, int height) {
  LatLongTrig t;
  for (int y = 0; y < height; ++y) {
    const double lat = latlong::Latitude(y, height);
    t.sin_lat.push_back(std::sin(lat));
    t.cos_lat.push_back(std::cos(lat));
  }
  for (int x = 0; x < width; ++x) {
    const double lon = latlong::Longitude(x, width);
    t.sin_lon.push_back(std::sin(lon));
    t.cos_lon.push_back(std::cos(lon));
  }
  return t;
}

}  // namespace skycal::clouds
