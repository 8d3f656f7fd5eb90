// Host-side preparation shared by both backends: the preset and request resolved into
// the model's SkyParams in double precision (sun disc radiance, ground radiance, ...).
#pragma once
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "skycal/render/sky_model.h"

namespace skycal::render {

// LUT access for the shared model source on the CPU (values widened to the scalar type).
struct CpuLutSource {
  const SkyLuts* luts;
  template <typename S>
  glsl::Vec3<S> texel(int lut, int row, int col) const {
    const std::vector<float>& t = lut == 0 ? luts->rayleigh : (lut == 1 ? luts->mie : luts->isotropic);
    const size_t i = (static_cast<size_t>(row) * luts->grid.n_gamma + col) * 3;
    return glsl::Vec3<S>(S(t[i]), S(t[i + 1]), S(t[i + 2]));
  }
};

using CpuSkyModel = model::SkyModel<double, CpuLutSource>;
using SkyParamsD = CpuSkyModel::SkyParams;

// Validates preset and request (throws skycal::Error) and resolves the parameters.
SkyParamsD ResolveSkyParams(const Preset& preset, const RenderRequest& request);

// Irradiance (lux per channel) on an upward horizontal plane from the sky alone (no sun
// disc), by midpoint quadrature over the upper hemisphere.
std::array<double, 3> SkyHorizontalIrradiance(const Preset& preset, const SkyParamsD& params);

}  // namespace skycal::render
