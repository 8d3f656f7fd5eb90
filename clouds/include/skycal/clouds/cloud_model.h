// C++ instantiation of the shared cloud model (clouds/model/*.glsl.h), a class template on
// the scalar type (double: the reference; float: the CPU path that takes the shader's
// decisions; ceres::Jet: the lighting fit) and the texture source, as render::SkyModel.
// TextureSource provides `template <class S> S texel(int texture, int index) const`
// (the float at `index` of a texture's array; CpuCloudTextures below for CloudNoise +
// WeatherMap) and `void packed(bool base, int texel, float out[4]) const` (the packed
// views, cloud_noise_packing.h); the model turns them into cloud_textures.glsl.h's hook.
#pragma once
#include "../../../../render/model/glsl_compat.h"
#include "skycal/clouds/cloud_noise_packing.h"
#include "skycal/clouds/cloud_textures.h"

namespace skycal::model {
using namespace skycal::glsl;  // the GLSL built-in names the shared source calls

template <typename ScalarT, typename TextureSource>
struct CloudModel {
  using Scalar = ScalarT;
  using vec3 = Vec3<Scalar>;

  explicit CloudModel(const TextureSource& source) : texture_source(source) {}
  const TextureSource& texture_source;

#include "../../../model/cloud_textures.glsl.h"
  // The shared source's texture hook (cloud_textures.glsl.h): base RGBA, the others RGB;
  // the packed views formed from them texel by texel (cloud_noise_packing.h).
  Texel4 cloud_texel4(int texture, int texel) const {
    if (texture >= CLOUD_TEX_BASE_PAIRS) {
      float v[4];
      texture_source.packed(texture == CLOUD_TEX_BASE_PAIRS, texel, v);
      Texel4 t;
      t.r = Scalar(v[0]);
      t.g = Scalar(v[1]);
      t.b = Scalar(v[2]);
      t.a = Scalar(v[3]);
      return t;
    }
    const int channels = texture == CLOUD_TEX_BASE ? 4 : 3;
    const int i = texel * channels;
    Texel4 t;
    t.r = texture_source.template texel<Scalar>(texture, i);
    t.g = texture_source.template texel<Scalar>(texture, i + 1);
    t.b = texture_source.template texel<Scalar>(texture, i + 2);
    t.a = channels == 4 ? texture_source.template texel<Scalar>(texture, i + 3) : Scalar(0.0);
    return t;
  }
#include "../../../model/cloud_shade_params.glsl.h"
#include "../../../model/cloud_geometry.glsl.h"
#include "../../../model/cloud_density.glsl.h"
#include "../../../model/cloud_lighting.glsl.h"
#include "../../../model/cloud_march.glsl.h"
};

}  // namespace skycal::model

namespace skycal::clouds {
using model::CloudModel;

// The CPU paths' texture source: the CloudNoise and WeatherMap arrays (layouts in
// cloud_textures.h), widened to the scalar type.
struct CpuCloudTextures {
  const float* base = nullptr;
  const float* detail = nullptr;
  const float* curl = nullptr;
  const float* weather = nullptr;
  CpuCloudTextures(const CloudNoise& noise, const WeatherMap& map)
      : base(noise.base.data()), detail(noise.detail.data()), curl(noise.curl.data()), weather(map.rgb.data()) {}
  template <typename S>
  S texel(int texture, int index) const {
    const float* t = texture == 0 ? base : (texture == 1 ? detail : (texture == 2 ? curl : weather));
    return S(t[index]);
  }
  // A BASE_PAIRS (base) or DETAIL_QUADS texel, packed from the arrays as the upload does.
  void packed(bool base_pairs, int texel, float out[4]) const {
    if (base_pairs) {
      BasePairTexel(base, texel, out);
    } else {
      DetailQuadTexel(detail, texel, out);
    }
  }
};

}  // namespace skycal::clouds
