// C++ instantiation of the shared model source render/model/sky_model.glsl.h, a class
// template on the scalar type (double for the CPU reference, ceres::Jet for the fit).
// LutSource provides `template <class S> glsl::Vec3<S> texel(int lut, int row, int col) const`.
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
  vec3 lut_texel(int lut, int row, int col) {
    return lut_source.template texel<Scalar>(lut, row, col);
  }

#include "../../../model/sky_model.glsl.h"
};

}  // namespace skycal::model
