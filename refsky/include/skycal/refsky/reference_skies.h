// Clear-sky references the game's model was not built from, for the fit's accuracy tests
// and benchmarks ("measure where users are"): the 15 CIE standard general skies, and the
// model drawn from single-scattering bakes of other atmospheres (aerosol amounts and scale
// heights the bundled preset was not baked with). Each is written as a lat-long reference
// frame (EXR with its sunDirection attribute), as `skycal capture` or `import` would.
#pragma once
#include <string>
#include <vector>

#include "skycal/core/latlong.h"
#include "skycal/refsky/cie_sky.h"
#include "skycal/render/preset.h"

namespace skycal::refsky {

// A CIE general sky of type t, grey (R = G = B = luminance, cd/m^2) with zenith luminance
// `zenith_cd_m2`, 0 below the horizon, width x width/2, and one bright pixel at the sun (a
// photograph's sun disc: without it fit::LoadReference could take a zenith-peaked sky's
// plateau for clipping). Throws skycal::Error when the sun is below the horizon (the CIE
// formulas are defined for 0 <= sun zenith <= 90 deg).
void WriteCieReference(const std::string& path, const CieSkyType& t, const latlong::Vec3d& sun, int width,
                       double zenith_cd_m2 = 5000.0);

// An atmosphere other than the bundled preset's, named by what changes.
struct AtmosphereVariant {
  std::string name;
  double mie_scattering_per_m;   // aerosol amount at sea level (bundled: 3.996e-6 1/m)
  double mie_scale_height_m;     // aerosol layer height (bundled: 1200 m)
  double haziness_g;             // the preset's g for the Mie lobe
};
// A range of turbidity-like aerosol amounts (0.25x to 8x the bundled) and layer heights.
std::vector<AtmosphereVariant> StandardAtmosphereVariants();

// The bundled grid baked from the variant's atmosphere (skycal bake), model ffxv.
render::Preset BakeVariant(const AtmosphereVariant& v);

// The preset rendered by the CPU reference (sun disc on, zero ground) at `sun`.
void WriteModelReference(const std::string& path, const render::Preset& preset, const latlong::Vec3d& sun, int width);

}  // namespace skycal::refsky
