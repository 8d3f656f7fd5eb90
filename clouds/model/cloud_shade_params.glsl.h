// Per-frame parameters of the cloud model, for GLSL and C++ (the common subset of
// render/model/glsl_compat.h). The host resolves them in double
// (clouds/src/resolved_clouds.cc); the shader reads them from a float buffer, the CPU
// paths take the same resolved values cast to their scalar type. Fields, units and
// meanings: cloud_shade_fields.glsl.h.
#define SC_FIELD(name) Scalar name;
#define SC_FIELD_VEC3(name) vec3 name;
#define SC_FIELD_INT(name) int name;
struct CloudShadeParams {
#include "cloud_shade_fields.glsl.h"
};
#undef SC_FIELD
#undef SC_FIELD_VEC3
#undef SC_FIELD_INT
