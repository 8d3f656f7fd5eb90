// Packed views of the cloud noise that the density reads (clouds/model/cloud_textures.glsl.h,
// CLOUD_TEX_BASE_PAIRS and CLOUD_TEX_DETAIL_QUADS): one 4-float texel holds what a trilinear
// read would otherwise load from 2 (base) or 4 (detail) texels. The C++ model packs texel by
// texel on the fly (CpuCloudTextures); the Vulkan renderer uploads whole packed arrays made
// by the same functions, so both backends read the same floats.
#pragma once
#include <vector>

#include "skycal/clouds/cloud_textures.h"

namespace skycal::clouds {

// Worley fbm weights of the base (G, B, A) and detail (R, G, B) octaves, formed in float in
// this order (the packed texel's value).
inline float BaseFbm(const float* rgba) { return rgba[1] * 0.625f + rgba[2] * 0.25f + rgba[3] * 0.125f; }
inline float DetailFbm(const float* rgb) { return rgb[0] * 0.625f + rgb[1] * 0.25f + rgb[2] * 0.125f; }

// BASE_PAIRS texel number `texel` ((z N + y) N + x): (R, fbm) at x, then at x + 1 wrapped.
inline void BasePairTexel(const float* base, int texel, float out[4]) {
  constexpr int n = CloudNoise::kBaseSize;
  const int x = texel & (n - 1);
  const int next = texel - x + ((x + 1) & (n - 1));
  out[0] = base[4 * texel];
  out[1] = BaseFbm(base + 4 * texel);
  out[2] = base[4 * next];
  out[3] = BaseFbm(base + 4 * next);
}

// DETAIL_QUADS texel number `texel` ((z N + y) N + x): the detail fbm at (x, y), (x + 1, y),
// (x, y + 1), (x + 1, y + 1) of slice z, wrapped.
inline void DetailQuadTexel(const float* detail, int texel, float out[4]) {
  constexpr int n = CloudNoise::kDetailSize;
  const int x = texel & (n - 1), y = (texel / n) & (n - 1), slice = texel - x - y * n;
  const int x1 = (x + 1) & (n - 1), y1 = (y + 1) & (n - 1);
  out[0] = DetailFbm(detail + 3 * (slice + y * n + x));
  out[1] = DetailFbm(detail + 3 * (slice + y * n + x1));
  out[2] = DetailFbm(detail + 3 * (slice + y1 * n + x));
  out[3] = DetailFbm(detail + 3 * (slice + y1 * n + x1));
}

// Whole packed arrays (4 floats per texel), for upload.
inline std::vector<float> PackBasePairs(const CloudNoise& noise) {
  constexpr int texels = CloudNoise::kBaseSize * CloudNoise::kBaseSize * CloudNoise::kBaseSize;
  std::vector<float> v(static_cast<size_t>(texels) * 4);
  for (int i = 0; i < texels; ++i) BasePairTexel(noise.base.data(), i, &v[4 * static_cast<size_t>(i)]);
  return v;
}
inline std::vector<float> PackDetailQuads(const CloudNoise& noise) {
  constexpr int texels = CloudNoise::kDetailSize * CloudNoise::kDetailSize * CloudNoise::kDetailSize;
  std::vector<float> v(static_cast<size_t>(texels) * 4);
  for (int i = 0; i < texels; ++i) DetailQuadTexel(noise.detail.data(), i, &v[4 * static_cast<size_t>(i)]);
  return v;
}

}  // namespace skycal::clouds
