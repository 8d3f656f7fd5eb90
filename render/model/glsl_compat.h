// C++ side of the GLSL/C++ common subset (C++ only; the shaders use GLSL built-ins).
//
// render/model/*.glsl.h are written once and compiled twice: by glslc into the compute
// shaders, and by the C++ compiler inside a class template on the scalar type (double,
// float or ceres::Jet), as in Bruneton's precomputed atmospheric scattering. This header
// supplies what GLSL has built in: vec2/vec3, dot/length/normalize, min/max/clamp/mix and
// the scalar math functions. Rules for the shared sources, which the Jet instantiation
// enforces at compile time:
//   - write every literal as Scalar(1.5), never a bare 1.5 next to a Scalar;
//   - no swizzles, no `out`/`inout` parameters (return structs instead);
//   - int <-> Scalar only through Scalar(i) and floor_to_int(x);
//   - constants through SC_CONST(name, value).
#pragma once
#include <cmath>

namespace skycal::glsl {

template <typename T>
struct Vec3 {
  T x, y, z;
  Vec3() : x(0.0), y(0.0), z(0.0) {}
  template <typename S>
  explicit Vec3(const S& s) : x(s), y(s), z(s) {}
  template <typename A, typename B, typename C>
  Vec3(const A& a, const B& b, const C& c) : x(a), y(b), z(c) {}
};

template <typename T> Vec3<T> operator+(const Vec3<T>& a, const Vec3<T>& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename T> Vec3<T> operator-(const Vec3<T>& a, const Vec3<T>& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename T> Vec3<T> operator-(const Vec3<T>& a) { return {-a.x, -a.y, -a.z}; }
template <typename T> Vec3<T> operator*(const Vec3<T>& a, const Vec3<T>& b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
template <typename T> Vec3<T> operator*(const Vec3<T>& a, const T& s) { return {a.x * s, a.y * s, a.z * s}; }
template <typename T> Vec3<T> operator*(const T& s, const Vec3<T>& a) { return {a.x * s, a.y * s, a.z * s}; }
template <typename T> Vec3<T> operator/(const Vec3<T>& a, const T& s) { return {a.x / s, a.y / s, a.z / s}; }

template <typename T> T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Scalar built-ins for double and float (ceres::Jet brings its own through ADL).
inline double sqrt(double x) { return std::sqrt(x); }
inline float sqrt(float x) { return std::sqrt(x); }
inline double exp(double x) { return std::exp(x); }
inline float exp(float x) { return std::exp(x); }
inline double log(double x) { return std::log(x); }
inline float log(float x) { return std::log(x); }
inline double asin(double x) { return std::asin(x); }
inline float asin(float x) { return std::asin(x); }
inline double cos(double x) { return std::cos(x); }
inline float cos(float x) { return std::cos(x); }
inline double sin(double x) { return std::sin(x); }
inline float sin(float x) { return std::sin(x); }
inline double floor(double x) { return std::floor(x); }
inline float floor(float x) { return std::floor(x); }
// GLSL's two-argument atan(y, x) is C's atan2.
inline double atan(double y, double x) { return std::atan2(y, x); }
inline float atan(float y, float x) { return std::atan2(y, x); }
template <typename J>
auto atan(const J& y, const J& x) -> decltype(atan2(y, x)) { return atan2(y, x); }

template <typename T> T length(const Vec3<T>& a) { return sqrt(dot(a, a)); }
template <typename T> Vec3<T> normalize(const Vec3<T>& a) { return a / length(a); }

template <typename T> T max(const T& a, const T& b) { return a < b ? b : a; }
template <typename T> T min(const T& a, const T& b) { return b < a ? b : a; }
template <typename T> T clamp(const T& x, const T& lo, const T& hi) { return min(max(x, lo), hi); }
template <typename T> T mix(const T& a, const T& b, const T& t) { return a + (b - a) * t; }
template <typename T> Vec3<T> mix(const Vec3<T>& a, const Vec3<T>& b, const T& t) { return a + (b - a) * t; }

inline int floor_to_int(double x) { return static_cast<int>(std::floor(x)); }
inline int floor_to_int(float x) { return static_cast<int>(std::floor(x)); }
template <typename J>
int floor_to_int(const J& x) { return floor_to_int(x.a); }  // ceres::Jet: value part

}  // namespace skycal::glsl

// Macros the shared sources use; the GLSL prelude (render/shaders/glsl_prelude.glsl.h)
// defines the same names for the shader side.
#define SC_CONST(name, value) static constexpr double name = value;
#define SC_CONST_INT(name, value) static constexpr int name = value;
