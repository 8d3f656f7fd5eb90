// Host-side preparation shared by every backend: parameters, march options, the preset's
// light and the request resolved in double into the model's CloudShadeParams, and that
// struct's float forms (the float CPU path's struct and the shader's parameter buffer),
// generated from the one field list clouds/model/cloud_shade_fields.glsl.h.
#pragma once
#include <type_traits>
#include <vector>

#include "skycal/clouds/cloud_model.h"
#include "skycal/clouds/cloud_renderer.h"

namespace skycal::clouds {

using CloudModelD = CloudModel<double, CpuCloudTextures>;
using CloudModelF = CloudModel<float, CpuCloudTextures>;
using CloudShadeD = CloudModelD::CloudShadeParams;
using CloudShadeF = CloudModelF::CloudShadeParams;

// Validates everything (throws skycal::Error naming the field) and resolves.
CloudShadeD ResolveCloudShade(const CloudScene& scene, const CloudRenderRequest& request);
// The same for several parameter sets over one scene (scene.params not read): the clear
// sky's SH-9, which depends on the preset and the sun alone, rendered once for all.
std::vector<CloudShadeD> ResolveCloudShades(const CloudScene& scene, const std::vector<const CloudParams*>& params,
                                            const CloudRenderRequest& request);

// Field by field conversion to another scalar type (float: what the shader reads;
// ceres::Jet: the lighting fit), generated from the field list.
template <typename Shade>
Shade CastCloudShade(const CloudShadeD& d) {
  using S = std::remove_cvref_t<decltype(Shade{}.planet_radius)>;
  Shade f{};
#define SC_FIELD(name) f.name = S(d.name);
#define SC_FIELD_VEC3(name) f.name = glsl::Vec3<S>(S(d.name.x), S(d.name.y), S(d.name.z));
#define SC_FIELD_INT(name) f.name = d.name;
#include "../model/cloud_shade_fields.glsl.h"
#undef SC_FIELD
#undef SC_FIELD_VEC3
#undef SC_FIELD_INT
  return f;
}
inline CloudShadeF ToFloat(const CloudShadeD& shade) { return CastCloudShade<CloudShadeF>(shade); }
// The shader's parameter buffer: the fields in list order, vec3 as 3 floats, ints as floats.
std::vector<float> PackCloudShade(const CloudShadeD& shade);

// Image-row and column direction tables (sin, cos of latitude per row, of longitude per
// column), computed in double like the sky's: both backends read the same numbers.
struct LatLongTrig {
  std::vector<double> sin_lat, cos_lat, sin_lon, cos_lon;
};
LatLongTrig MakeLatLongTrig(int width, int height);

}  // namespace skycal::clouds
