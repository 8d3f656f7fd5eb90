#include "skycal/refsky/reference_skies.h"

#include <algorithm>
#include <cmath>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/render/atmosphere_bake.h"
#include "skycal/render/renderer.h"

namespace skycal::refsky {

// The bright sun pixel, x the zenith luminance: any unique peak will do (a pixel-averaged
// real sun disc is ~1e4-1e5 x Lz).
constexpr double kSunPixel = 1000.0;

void WriteCieReference(const std::string& path, const CieSkyType& t, const latlong::Vec3d& sun, int width,
                       double zenith_cd_m2) {
  if (!(sun[1] >= 0.0)) throw Error(path + ": the CIE general sky needs the sun at or above the horizon");
  const int height = width / 2;
  capture::LatLongFrame f;
  f.radiance = ImageRGB(width, height);
  double best_mu = -2.0;
  int sun_x = 0, sun_y = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const auto v = latlong::PixelDirection(x, y, width, height);
      const double l = v[1] > 0.0 ? zenith_cd_m2 * CieRelativeLuminance(t, v, sun) : 0.0;
      for (int c = 0; c < 3; ++c) f.radiance.at(x, y, c) = static_cast<float>(l);
      const double mu = v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2];
      if (mu > best_mu) best_mu = mu, sun_x = x, sun_y = y;
    }
  }
  for (int c = 0; c < 3; ++c) f.radiance.at(sun_x, sun_y, c) = static_cast<float>(kSunPixel * zenith_cd_m2);
  f.sun_direction = sun;
  capture::WriteLatLongFrame(path, f);
}

std::vector<AtmosphereVariant> StandardAtmosphereVariants() {
  return {{"clear_0.25x_aerosol", 1.0e-6, 1200.0, 0.8},
          {"hazy_4x_aerosol", 1.6e-5, 1200.0, 0.78},
          {"turbid_8x_aerosol_high_layer", 3.2e-5, 2500.0, 0.72}};
}

render::Preset BakeVariant(const AtmosphereVariant& v) {
  render::Preset p;
  p.luts.Resize(render::LutGrid{});  // the bundled grid: 37 x 32, sun zenith to 108 deg
  render::AtmosphereOptions a;
  a.mie_scattering_per_m = v.mie_scattering_per_m;
  a.mie_extinction_per_m = v.mie_scattering_per_m / 0.9;  // single-scattering albedo 0.9 (Hillaire 2020)
  a.mie_scale_height_m = v.mie_scale_height_m;
  render::BakeSingleScattering(a, p.luts);
  p.name = v.name;
  p.haziness_g = v.haziness_g;
  p.variant = render::ModelVariant::kFfxv;
  return p;
}

void WriteModelReference(const std::string& path, const render::Preset& preset, const latlong::Vec3d& sun, int width) {
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = width;
  req.height = width / 2;
  req.ground = render::GroundMode::kZero;
  capture::LatLongFrame f;
  f.radiance = cpu->Render(preset, req);
  f.sun_direction = sun;
  capture::WriteLatLongFrame(path, f);
}

}  // namespace skycal::refsky
