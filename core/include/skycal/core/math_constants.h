// Mathematical constants and angle units, one definition for the project's C++ (the GLSL
// model sources carry their own literal, SC_PI in render/model/sky_model.glsl.h, which a
// test compares against kPi).
#pragma once
#include <numbers>

namespace skycal {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kRadiansPerDegree = kPi / 180.0;
inline constexpr double kDegreesPerRadian = 180.0 / kPi;

// Evaluated as deg * pi / 180 and rad * 180 / pi, the form the project's formulas write
// inline (multiplying by kRadiansPerDegree can differ from it in the last bit).
constexpr double DegToRad(double deg) { return deg * kPi / 180.0; }
constexpr double RadToDeg(double rad) { return rad * 180.0 / kPi; }

}  // namespace skycal
