#version 450
// Renders the sky model into a full-sphere lat-long image (OpenEXR LatLong convention),
// one invocation per pixel. The model itself is render/model/sky_model.glsl.h, the same
// source the CPU reference and the fit compile as C++.
#extension GL_GOOGLE_include_directive : require

// Workgroup size: specialization constants 0 and 1, set by the host (vulkan_renderer.cc).
layout(local_size_x_id = 0, local_size_y_id = 1, local_size_z = 1) in;

#define SC_UNIFORM_VEC4(name) vec4 name;
#define SC_UNIFORM_IVEC4(name) ivec4 name;
// The per-render parameters: a read-only storage buffer (vec4/ivec4 members: std430 is
// std140 here), not a uniform block. On lavapipe (Mesa 22.3) this block as a uniform buffer
// rewritten every render grew the driver's heap at every dispatch and made small renders
// slower; as storage it stays flat (tests/vulkan_renderers_test.cc; the numbers in
// bench/results/gpu_lavapipe.md). All of a workgroup reads the same words either way.
layout(std430, set = 0, binding = 0) readonly buffer SkyUniformBlock {
#include "sky_uniforms.glsl.h"
} U;

// The LUTs at this frame's sun position, interpolated between rows by the host:
// [table (rayleigh, mie, isotropic)][column] -> rgb (w unused). A uniform block: every
// invocation of a workgroup (one image row) reads the same entries.
#include "limits.glsl.h"
layout(std140, set = 0, binding = 1) uniform LutSliceBlock { vec4 lut_slice[3 * SC_MAX_LUT_COLUMNS]; };
// Output: interleaved RGB float, row 0 at the top.
layout(std430, set = 0, binding = 2) writeonly buffer OutBuffer { float out_rgb[]; };
// Direction tables filled by the host in double: (sin, cos) of latitude per row
// [0, height), then (sin, cos) of longitude per column [height, height + width).
layout(std430, set = 0, binding = 3) readonly buffer TrigBuffer { vec2 trig[]; };

#include "glsl_prelude.glsl.h"

vec3 lut_column_texel(int lut, int row0, float frow, int col) {
  return lut_slice[lut * U.sizes.x + col].xyz;
}

#include "sky_model.glsl.h"

void main() {
  int x = int(gl_GlobalInvocationID.x);
  // One image row per workgroup (local size (N, 1)): y is uniform across the workgroup,
  // so everything that depends only on the row (latitude, the LUT column and its loads)
  // is uniform too, and the compiler emits scalar loads instead of per-lane gathers.
  // Workgroup row r draws image row (r * stride) mod height (gpu/workgroup_order.h:
  // lavapipe's threads each take a contiguous block of workgroups; this spreads each block
  // over the sky and the ground alike).
  int y = int((gl_WorkGroupID.y * uint(U.order.x)) % gl_NumWorkGroups.y);
  int width = U.sizes.z;
  int height = U.sizes.w;

  // The parameters are loaded before the bounds check: after a divergent `return`,
  // lavapipe turns uniform-block loads into per-lane loads (measured on the cloud shader,
  // clouds_latlong.comp); loaded while every lane is active they stay scalar.
  SkyParams p;
  p.sun_dir = U.sun_dir.xyz;
  p.haziness_g = U.model.x;
  p.isotropic_weight = U.model.y;
  p.overcast_weight = U.model.z;
  p.overcast_zenith = U.model.w;
  p.sun_one_minus_cos_radius = U.sun_disc.x;
  p.sun_radius = U.sun_disc.y;
  p.sun_limb_u = U.sun_disc.z;
  p.sun_centre_radiance = U.sun_radiance.xyz;
  p.ground_radiance = U.ground.xyz;
  p.lut_one_minus_cos_theta_max = U.lut_grid.x;
  p.lut_n_theta = U.sizes.y;
  p.lut_n_gamma = U.sizes.x;
  if (x >= width || y >= height) return;

  vec2 lat = trig[y];
  vec2 lon = trig[height + x];
  vec3 l = radiance(latlong_direction_from_trig(lat.x, lat.y, lon.x, lon.y), p);
  int o = (y * width + x) * 3;
  out_rgb[o] = l.x;
  out_rgb[o + 1] = l.y;
  out_rgb[o + 2] = l.z;
}
