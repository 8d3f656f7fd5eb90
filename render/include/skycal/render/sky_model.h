// C++ instantiation of the shared model source render/model/sky_model.glsl.h, a class
// template on the scalar type (double for the CPU reference, ceres::Jet for the fit).
// LutSource provides `template <class S> glsl::Vec3<S> texel(int lut, int row, int col) const`
// (the LUT node value, as scalar type S: double for rendering, Jet for fitting LUT entries).
#pragma once
#include "../../../model/glsl_compat.h"

namespace skycal::model {
using namespace skycal::glsl;  // the GLSL built-in names the shared source calls

template <typename ScalarT, typename LutSource>
struct SkyModel {
  using Scalar = ScalarT;
  using vec3 = Vec3<Scalar>;

  explicit SkyModel(const LutSource& source) : lut_source(source) {}
  const LutSource& lut_source;
  // The shared source's LUT hook: rows interpolated here, columns by the shared code.
  vec3 lut_column_texel(int lut, int row0, Scalar frow, int col) {
    return mix(lut_source.template texel<Scalar>(lut, row0, col), lut_source.template texel<Scalar>(lut, row0 + 1, col),
               frow);
  }

#include "../../../model/sky_model.glsl.h"
};

}  // namespace skycal::model
