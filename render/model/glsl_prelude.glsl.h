// GLSL side of the GLSL/C++ common subset: the names render/model/glsl_compat.h gives
// C++. Include first in every compute shader that includes a shared model source.
#define Scalar float
#define SC_CONST(name, value) const float name = value;
int floor_to_int(float x) { return int(floor(x)); }
#define SC_CONST_INT(name, value) const int name = value;
