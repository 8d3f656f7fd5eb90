// Luminance Y of scene-linear RGB with Rec.709 primaries and D65 white (the primaries of
// sRGB too): Y = 0.2126 R + 0.7152 G + 0.0722 B, the weights as ITU-R BT.709-6 (Part 1,
// item 3.2, "derivation of luminance signal") publishes them, rounded to 4 digits (the Y
// row of the RGB -> CIE XYZ matrix of IEC 61966-2-1). The project's one copy of them: the
// sky model's radiance channels are in these primaries, so Y of a radiance in cd/m^2 is
// a luminance in cd/m^2 and Y of an irradiance in lux is an illuminance in lux.
#pragma once
#include <array>
#include <type_traits>

namespace skycal {

inline constexpr std::array<double, 3> kRec709LuminanceWeights = {0.2126, 0.7152, 0.0722};

// Y of (r, g, b), evaluated left to right as w_r r + w_g g + w_b b. A floating-point T
// computes in T (for float: the float literals 0.2126f, ...; call Rec709Luminance<double>
// to widen float pixels first); other T (ceres::Jet, ...) scale by the double weights.
template <typename T>
constexpr T Rec709Luminance(const T& r, const T& g, const T& b) {
  constexpr const std::array<double, 3>& w = kRec709LuminanceWeights;
  if constexpr (std::is_floating_point_v<T>) {
    return T(w[0]) * r + T(w[1]) * g + T(w[2]) * b;
  } else {
    return w[0] * r + w[1] * g + w[2] * b;
  }
}

template <typename T>
constexpr T Rec709Luminance(const std::array<T, 3>& rgb) {
  return Rec709Luminance(rgb[0], rgb[1], rgb[2]);
}

}  // namespace skycal
