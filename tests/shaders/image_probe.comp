#version 450
// Test shader for the cloud march's sampled-image readers (clouds/model/cloud_textures_hw.glsl.h;
// tests/sampled_image_test.cc): for each probe point (u, v, w) in texel units, the readers
// the march calls, at the coordinates the test's CPU side reads with the shared source.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
// 0: probe points, vec4 (u, v, w, unused); the count is the buffer's.
layout(std430, set = 0, binding = 0) readonly buffer Points { vec4 points[]; };
layout(set = 0, binding = 1) uniform sampler3D base_image;
layout(set = 0, binding = 2) uniform sampler3D detail_image;
layout(set = 0, binding = 3) uniform sampler2D curl_image;
layout(set = 0, binding = 4) uniform sampler2D weather_image;
// 5: 9 floats a point: base R, base fbm, detail fbm, curl rgb, weather rgb.
layout(std430, set = 0, binding = 5) writeonly buffer Out { float out_values[]; };

#include "glsl_prelude.glsl.h"
#include "cloud_textures.glsl.h"
#include "cloud_textures_hw.glsl.h"

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(points.length())) return;
  vec4 p = points[i];
  ivec2 ws = textureSize(weather_image, 0);
  BaseNoise b = sample_base_noise(p.x, p.y, p.z);
  float detail = sample_detail_fbm(p.x * 0.25, p.y * 0.25, p.z * 0.25);
  Texel4 curl = sample_image(CLOUD_TEX_CURL, CLOUD_CURL_SIZE, CLOUD_CURL_SIZE, p.x, p.z);
  Texel4 weather = sample_image(CLOUD_TEX_WEATHER, ws.x, ws.y, p.x * 0.5, p.z * 0.5);
  float o[9] = float[9](b.r, b.fbm, detail, curl.r, curl.g, curl.b, weather.r, weather.g, weather.b);
  for (int k = 0; k < 9; ++k) out_values[9 * i + uint(k)] = o[k];
}
