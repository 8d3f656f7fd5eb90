#version 450
// Renders the cloudscape into a full-sphere lat-long (OpenEXR LatLong convention), one
// invocation per pixel: in-scattered radiance and transmittance. The model is
// clouds/model/*.glsl.h, the same source the CPU paths (and the fit) compile as C++.
#extension GL_GOOGLE_include_directive : require

// Workgroup size: specialization constants 0 and 1 (vulkan_cloud_renderer.cc: 8 x 8 tiles).
layout(local_size_x_id = 0, local_size_y_id = 1, local_size_z = 1) in;

// 0: per layer (gl_WorkGroupID.z) a block: CloudShadeParams in cloud_shade_fields.glsl.h's
// order, then image width, height and the workgroup row stride.
layout(std430, set = 0, binding = 0) readonly buffer ParamBuffer { float P[]; };
#ifdef CLOUD_HARDWARE_FILTER
// 1-4: the textures as sampled images (vulkan_cloud_renderer.cc: RGBA32F, the RGB ones
// padded with a zero channel), read through the hardware's linear filter with repeat
// addressing: the base noise (RGBA) and the detail noise (RGB) 3D, the curl noise and the
// weather map 2D. The readers are defined below, after cloud_textures.glsl.h's types.
layout(set = 0, binding = 1) uniform sampler3D base_image;
layout(set = 0, binding = 2) uniform sampler3D detail_image;
layout(set = 0, binding = 3) uniform sampler2D curl_image;
layout(set = 0, binding = 4) uniform sampler2D weather_image;
#else
// 1-4: the textures in cloud_textures.h's texel order, one vec4 per texel (the host pads
// the RGB ones with a zero channel): exact filtering in the shared source, no filtering by
// a sampler (texelFetch only). Texel buffers, not storage buffers: lavapipe compiles a
// storage-buffer load at a per-lane index into a bounds-checked scalar loop over the lanes
// for each component, each element inserted into the vector through the stack (~30
// instructions and a store-forwarding stall per lane and component: 32 per vec4 texel);
// texelFetch gathers one 16-byte load per lane and transposes. Same texels (parity maxima
// unchanged to the digit); default_cloudy at 512x256, game march, one process, loaded 2 cores:
// 2.8 s -> 0.8-0.95 s per render (perf: ~90% of lavapipe's time was in those loops).
// The density reads packed views (cloud_textures.glsl.h, cloud_noise_packing.h): binding 1
// the base's (R, fbm) pairs (the cirrus sheet reads its R there too), binding 2 the detail
// fbm's 2x2 quads.
layout(set = 0, binding = 1) uniform samplerBuffer base_pairs;
layout(set = 0, binding = 2) uniform samplerBuffer detail_quads;
layout(set = 0, binding = 3) uniform samplerBuffer curl_noise;
layout(set = 0, binding = 4) uniform samplerBuffer weather_map;
#endif
// 5: (sin, cos) of latitude per row [0, height), of longitude per column [height, height + width),
// filled by the host in double (shader sin/cos carry ~1e-6 error).
layout(std430, set = 0, binding = 5) readonly buffer TrigBuffer { vec2 trig[]; };
// 6: output, 4 floats per pixel, the layers' images one after another: radiance rgb
// (cd/m^2), transmittance.
layout(std430, set = 0, binding = 6) writeonly buffer OutBuffer { float out_rt[]; };

#include "glsl_prelude.glsl.h"

#ifndef CLOUD_HARDWARE_FILTER
struct Texel4 {
  float r;
  float g;
  float b;
  float a;
};

Texel4 cloud_texel4(int texture, int texel) {
  vec4 v;
  // `texture` is a constant at every call: the chain folds away.
  if (texture == 4) v = texelFetch(base_pairs, texel);
  else if (texture == 5) v = texelFetch(detail_quads, texel);
  else if (texture == 2) v = texelFetch(curl_noise, texel);
  else v = texelFetch(weather_map, texel);  // 3 (0 and 1, the raw base and detail, are not read here)
  Texel4 t;
  t.r = v.x;
  t.g = v.y;
  t.b = v.z;
  t.a = v.w;
  return t;
}

#define CLOUD_TEXEL4_DECLARED
#endif
#include "cloud_textures.glsl.h"
#ifdef CLOUD_HARDWARE_FILTER
#include "cloud_textures_hw.glsl.h"
#endif

#include "cloud_shade_params.glsl.h"
#include "cloud_geometry.glsl.h"
#include "cloud_density.glsl.h"
#include "cloud_lighting.glsl.h"
#include "cloud_march.glsl.h"

CloudShadeParams load_params(int base) {
  CloudShadeParams p;
  int k = 0;
#define SC_FIELD(name) p.name = P[base + k]; k += 1;
#define SC_FIELD_VEC3(name) p.name = vec3(P[base + k], P[base + k + 1], P[base + k + 2]); k += 3;
#define SC_FIELD_INT(name) p.name = int(P[base + k]); k += 1;
#include "cloud_shade_fields.glsl.h"
#undef SC_FIELD
#undef SC_FIELD_VEC3
#undef SC_FIELD_INT
  return p;
}

int param_count() {
  int k = 0;
#define SC_FIELD(name) k += 1;
#define SC_FIELD_VEC3(name) k += 3;
#define SC_FIELD_INT(name) k += 1;
#include "cloud_shade_fields.glsl.h"
#undef SC_FIELD
#undef SC_FIELD_VEC3
#undef SC_FIELD_INT
  return k;
}

void main() {
  // Layer z of a batch (CloudRenderer::RenderEach): its parameter block (the shade, then
  // width, height and the row stride) and its image; a single render is layer 0.
  int n = param_count();
  int layer = int(gl_WorkGroupID.z);
  int base = layer * (n + 3);
  int width = int(P[base + n]);
  int height = int(P[base + n + 1]);
  // The parameters before any control flow: lavapipe loads a uniform-indexed buffer
  // element once for all lanes only while every lane is known active; after the bounds
  // check's return it loads each of the ~90 fields lane by lane (a scalar loop through the
  // stack per field), which cost ~20% of the render.
  CloudShadeParams p = load_params(base);
  int x = int(gl_GlobalInvocationID.x);
  // Workgroup row r draws tile row (r * stride) mod rows (gpu/workgroup_order.h: lavapipe's
  // threads each take a contiguous block of workgroups; this spreads every block over the
  // sky and the ground alike). uint arithmetic: rows * stride < 2^32 for any image we accept.
  uint tile_row = (gl_WorkGroupID.y * uint(P[base + n + 2])) % gl_NumWorkGroups.y;
  int y = int(tile_row * gl_WorkGroupSize.y + gl_LocalInvocationID.y);
  if (x >= width || y >= height) return;
  vec2 lat = trig[y];
  vec2 lon = trig[height + x];
  // The same products as the C++ paths (cpu_cloud_renderer.cc), in the same order.
  vec3 view = vec3(lon.x * lat.y, lat.x, lon.y * lat.y);
  CloudResult r = cloud_march(view, p);
  int o = ((layer * height + y) * width + x) * 4;
  out_rt[o] = r.radiance.x;
  out_rt[o + 1] = r.radiance.y;
  out_rt[o + 2] = r.radiance.z;
  out_rt[o + 3] = r.transmittance;
}
