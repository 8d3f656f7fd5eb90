// CIELAB and colour differences for linear Rec.709 values (the working space): the
// colour-chart correction reports how far a chart's patches are from their published
// values in CIEDE2000 units.
#pragma once
#include <array>

namespace skycal::capture {

using Rgb = std::array<double, 3>;

// Linear Rec.709 / sRGB primaries, D65 white (IEC 61966-2-1's matrix) -> CIE XYZ (Y of the
// white (1, 1, 1) = 1) -> CIELAB relative to that D65 white (CIE 15:2004).
Rgb LinearRec709ToXyz(const Rgb& rgb);
Rgb XyzToLab(const Rgb& xyz);
inline Rgb LinearRec709ToLab(const Rgb& rgb) { return XyzToLab(LinearRec709ToXyz(rgb)); }

// CIE 1976 colour difference: Euclidean distance in L*a*b*.
double DeltaE76(const Rgb& lab1, const Rgb& lab2);
// CIEDE2000 (CIE 142-2001), k_L = k_C = k_H = 1, with the hue conventions of Sharma, Wu &
// Dalal, "The CIEDE2000 color-difference formula: implementation notes, supplementary test
// data, and mathematical observations" (2005), whose test pairs tests/color_chart_test.cc uses.
double DeltaE2000(const Rgb& lab1, const Rgb& lab2);

// The sRGB transfer function (IEC 61966-2-1): encoded [0, 1] <-> linear [0, 1].
double SrgbDecode(double v);
double SrgbEncode(double v);

}  // namespace skycal::capture
