// C++ view of the uniform block in render/model/sky_uniforms.glsl.h (the one layout
// source). std140 places vec4/ivec4 members at consecutive 16-byte offsets; the asserts
// below fail the build if this struct ever stops matching that.
#pragma once
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "resolved_sky.h"
#include "skycal/gpu/workgroup_order.h"

namespace skycal::render {

struct alignas(16) SkyUniforms {
#define SC_UNIFORM_VEC4(name) float name[4];
#define SC_UNIFORM_IVEC4(name) int32_t name[4];
#include "../model/sky_uniforms.glsl.h"
#undef SC_UNIFORM_VEC4
#undef SC_UNIFORM_IVEC4
};

inline constexpr int kSkyUniformRecords = 0
#define SC_UNIFORM_VEC4(name) +1
#define SC_UNIFORM_IVEC4(name) +1
#include "../model/sky_uniforms.glsl.h"
#undef SC_UNIFORM_VEC4
#undef SC_UNIFORM_IVEC4
    ;

static_assert(std::is_standard_layout_v<SkyUniforms> && std::is_trivially_copyable_v<SkyUniforms>);
static_assert(sizeof(SkyUniforms) == 16 * kSkyUniformRecords, "std140: one 16-byte record per member");
static_assert(offsetof(SkyUniforms, model) == 16 && offsetof(SkyUniforms, order) == 16 * (kSkyUniformRecords - 1),
              "std140 offsets");

// Packs resolved parameters (double) into the float uniform block.
inline SkyUniforms PackSkyUniforms(const SkyParamsD& p, int width, int height) {
  SkyUniforms u{};
  auto set = [](float* dst, double a, double b, double c, double d) {
    dst[0] = static_cast<float>(a); dst[1] = static_cast<float>(b);
    dst[2] = static_cast<float>(c); dst[3] = static_cast<float>(d);
  };
  set(u.sun_dir, p.sun_dir.x, p.sun_dir.y, p.sun_dir.z, 0.0);
  set(u.model, p.haziness_g, p.isotropic_weight, p.overcast_weight, p.overcast_zenith);
  set(u.sun_disc, p.sun_one_minus_cos_radius, p.sun_radius, p.sun_limb_u, 0.0);
  set(u.sun_radiance, p.sun_centre_radiance.x, p.sun_centre_radiance.y, p.sun_centre_radiance.z, 0.0);
  set(u.ground, p.ground_radiance.x, p.ground_radiance.y, p.ground_radiance.z, 0.0);
  set(u.lut_grid, p.lut_one_minus_cos_theta_max, 0.0, 0.0, 0.0);
  u.sizes[0] = p.lut_n_gamma;
  u.sizes[1] = p.lut_n_theta;
  u.sizes[2] = width;
  u.sizes[3] = height;
  // One workgroup per image row (vulkan_renderer.cc): the stride over `height` rows.
  u.order[0] = static_cast<int32_t>(gpu::WorkgroupRowStride(static_cast<uint32_t>(height)));
  return u;
}

}  // namespace skycal::render
