// GLSL only: the three texture readers that clouds/model/cloud_textures.glsl.h leaves to a
// shader compiled with CLOUD_HARDWARE_FILTER, on the sampled images the includer declares
// (base_image and detail_image: sampler3D; curl_image and weather_image: sampler2D; RGBA32F,
// RGB padded with a zero channel; linear filter, repeat addressing). Included after
// cloud_textures.glsl.h (its Texel4, BaseNoise and texture numbers), by the march
// (clouds_latlong.comp) and by the filter's parity probe (tests/shaders/image_probe.comp).
//
// Texel coordinates (texel centres at i + 0.5, as wrap_axis) divided by the size (a power of
// two: exact) give the sampler's normalized coordinates; the fbm is formed from the filtered
// channels with cloud_noise_packing.h's weights (filtering is linear: the same value up to
// rounding and the filter's weight precision).
Texel4 texel4_from(vec4 v) {
  Texel4 t;
  t.r = v.x;
  t.g = v.y;
  t.b = v.z;
  t.a = v.w;
  return t;
}

BaseNoise sample_base_noise(float u, float v, float w) {
  vec4 t = textureLod(base_image, vec3(u, v, w) / float(CLOUD_BASE_SIZE), 0.0);
  BaseNoise b;
  b.r = t.x;
  b.fbm = t.y * 0.625 + t.z * 0.25 + t.w * 0.125;
  return b;
}

float sample_detail_fbm(float u, float v, float w) {
  vec4 t = textureLod(detail_image, vec3(u, v, w) / float(CLOUD_DETAIL_SIZE), 0.0);
  return t.x * 0.625 + t.y * 0.25 + t.z * 0.125;
}

Texel4 sample_image(int tex, int width, int height, float u, float v) {
  vec2 uv = vec2(u / float(width), v / float(height));
  // `tex` is a constant at every call: the branch folds away.
  if (tex == CLOUD_TEX_CURL) return texel4_from(textureLod(curl_image, uv, 0.0));
  return texel4_from(textureLod(weather_image, uv, 0.0));
}
