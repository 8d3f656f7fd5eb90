#include "resolved_sky.h"

#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"
#include "skycal/render/sky_params.h"

namespace skycal::render {

const char* ToString(Backend b) { return b == Backend::kVulkan ? "vulkan" : "cpu"; }

Backend ParseBackend(const std::string& name, const std::string& what) {
  if (name == "vulkan") return Backend::kVulkan;
  if (name == "cpu") return Backend::kCpu;
  throw Error(what + ": unknown backend '" + name + "' (expected vulkan or cpu)");
}

bool RenderRequest::IsValid(std::string* why) const {
  if (width < 2 || height < 2 || width > 32768 || height > 16384) {
    *why = "image size " + std::to_string(width) + "x" + std::to_string(height) +
           " (expected width 2..32768 and height 2..16384 pixels)";
    return false;
  }
  const double n = std::sqrt(sun_dir[0] * sun_dir[0] + sun_dir[1] * sun_dir[1] + sun_dir[2] * sun_dir[2]);
  if (!std::isfinite(n) || n < 1e-9) {
    *why = "sun direction is not a finite, non-zero vector";
    return false;
  }
  return true;
}

std::array<double, 3> SkyHorizontalIrradiance(const Preset& preset, const SkyParamsD& params) {
  CpuLutSource src{&preset.luts};
  CpuSkyModel m(src);
  // Midpoint rule on (elevation, azimuth); 48 x 96 nodes keep the error of smooth skies
  // well under 0.1% (the narrow Mie peak near the sun is the least resolved part).
  constexpr int kElev = 48, kAz = 96;
  std::array<double, 3> e{};
  for (int i = 0; i < kElev; ++i) {
    const double el = (i + 0.5) * (0.5 * kPi / kElev);
    const double w = std::cos(el) * std::sin(el) * (0.5 * kPi / kElev) * (2.0 * kPi / kAz);
    for (int j = 0; j < kAz; ++j) {
      const double az = (j + 0.5) * (2.0 * kPi / kAz);
      const glsl::Vec3<double> v(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
      const auto l = m.sky_radiance(v, params);
      e[0] += w * l.x;
      e[1] += w * l.y;
      e[2] += w * l.z;
    }
  }
  return e;
}

SkyParamsD ResolveSkyParams(const Preset& preset, const RenderRequest& request) {
  std::string why;
  if (!request.IsValid(&why)) throw Error("render request: " + why);
  ValidatePreset(preset, "preset '" + preset.name + "'");
  const auto sun = latlong::Normalized(request.sun_dir, "sun direction");

  SkyParamsD p = SkyParamsFromPreset<SkyParamsD>(preset);
  p.sun_dir = glsl::Vec3<double>(sun[0], sun[1], sun[2]);

  // Direct sun illuminance at normal incidence (lux per channel) and disc radiance.
  // Linear limb darkening on a small disc: E = L0 * Omega * (1 - u/3), Omega = 2 pi (1 - cos R).
  const double sun_zenith = std::atan2(std::hypot(sun[0], sun[2]), sun[1]);
  const auto transmittance = SunTransmittance(preset.luts, sun_zenith);
  std::array<double, 3> e_sun{};
  for (int c = 0; c < 3; ++c) e_sun[c] = preset.sun_illuminance_lux * preset.sun_tint_rgb[c] * transmittance[c];
  const double omega = 2.0 * kPi * p.sun_one_minus_cos_radius;
  const double to_radiance = request.sun_disc ? 1.0 / (omega * (1.0 - preset.sun_limb_darkening / 3.0)) : 0.0;
  p.sun_centre_radiance = glsl::Vec3<double>(e_sun[0] * to_radiance, e_sun[1] * to_radiance, e_sun[2] * to_radiance);

  p.ground_radiance = glsl::Vec3<double>(0.0);
  if (request.ground == GroundMode::kLit) {
    const auto e_sky = SkyHorizontalIrradiance(preset, p);
    const double cos_sun = std::max(sun[1], 0.0);
    const double k = preset.ground_albedo / kPi;
    p.ground_radiance = glsl::Vec3<double>(k * (e_sun[0] * cos_sun + e_sky[0]), k * (e_sun[1] * cos_sun + e_sky[1]),
                                           k * (e_sun[2] * cos_sun + e_sky[2]));
  }
  return p;
}

}  // namespace skycal::render
