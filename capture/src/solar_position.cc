// NREL's Solar Position Algorithm (Reda & Andreas 2004), written from the paper. The
// periodic-term tables are the paper's appendix tables A4.2 (Earth: L0..L5, B0..B1,
// R0..R4; each term A cos(B + C * JME)) and A4.3 (nutation: the multiples Y0..Y4 of the
// arguments X0..X4 and the coefficients a, b, c, d). Step numbers "3.x" are the paper's.
// ComputeSolarPosition follows the paper's steps 3.1..3.16 in one function, as published, so
// it can be checked against the paper line by line; it is exempt from the house's 80-line
// limit on functions.
#include "skycal/capture/solar_position.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

namespace skycal::capture {
namespace {

constexpr double kSunRadiusDeg = 0.26667;  // apparent solar radius (refraction cut-off, as in the reference code)

double Rad(double deg) { return deg * (kPi / 180.0); }
double Deg(double rad) { return rad * (180.0 / kPi); }
// Degrees into [0, 360).
double Wrap360(double deg) {
  double r = std::fmod(deg, 360.0);
  if (r < 0.0) r += 360.0;
  return r >= 360.0 ? 0.0 : r;
}

// ---- Table A4.2: Earth periodic terms, A cos(B + C * JME) (A in 1e-8 rad or AU). ----
struct Term {
  double a, b, c;
};

constexpr Term kL0[] = {
    {175347046.0, 0, 0}, {3341656.0, 4.6692568, 6283.07585}, {34894.0, 4.6261, 12566.1517},
    {3497.0, 2.7441, 5753.3849}, {3418.0, 2.8289, 3.5231}, {3136.0, 3.6277, 77713.7715},
    {2676.0, 4.4181, 7860.4194}, {2343.0, 6.1352, 3930.2097}, {1324.0, 0.7425, 11506.7698},
    {1273.0, 2.0371, 529.691}, {1199.0, 1.1096, 1577.3435}, {990, 5.233, 5884.927},
    {902, 2.045, 26.298}, {857, 3.508, 398.149}, {780, 1.179, 5223.694},
    {753, 2.533, 5507.553}, {505, 4.583, 18849.228}, {492, 4.205, 775.523},
    {357, 2.92, 0.067}, {317, 5.849, 11790.629}, {284, 1.899, 796.298},
    {271, 0.315, 10977.079}, {243, 0.345, 5486.778}, {206, 4.806, 2544.314},
    {205, 1.869, 5573.143}, {202, 2.458, 6069.777}, {156, 0.833, 213.299},
    {132, 3.411, 2942.463}, {126, 1.083, 20.775}, {115, 0.645, 0.98},
    {103, 0.636, 4694.003}, {102, 0.976, 15720.839}, {102, 4.267, 7.114},
    {99, 6.21, 2146.17}, {98, 0.68, 155.42}, {86, 5.98, 161000.69},
    {85, 1.3, 6275.96}, {85, 3.67, 71430.7}, {80, 1.81, 17260.15},
    {79, 3.04, 12036.46}, {75, 1.76, 5088.63}, {74, 3.5, 3154.69},
    {74, 4.68, 801.82}, {70, 0.83, 9437.76}, {62, 3.98, 8827.39},
    {61, 1.82, 7084.9}, {57, 2.78, 6286.6}, {56, 4.39, 14143.5},
    {56, 3.47, 6279.55}, {52, 0.19, 12139.55}, {52, 1.33, 1748.02},
    {51, 0.28, 5856.48}, {49, 0.49, 1194.45}, {41, 5.37, 8429.24},
    {41, 2.4, 19651.05}, {39, 6.17, 10447.39}, {37, 6.04, 10213.29},
    {37, 2.57, 1059.38}, {36, 1.71, 2352.87}, {36, 1.78, 6812.77},
    {33, 0.59, 17789.85}, {30, 0.44, 83996.85}, {30, 2.74, 1349.87},
    {25, 3.16, 4690.48},
};
constexpr Term kL1[] = {
    {628331966747.0, 0, 0}, {206059.0, 2.678235, 6283.07585}, {4303.0, 2.6351, 12566.1517},
    {425.0, 1.59, 3.523}, {119.0, 5.796, 26.298}, {109.0, 2.966, 1577.344},
    {93, 2.59, 18849.23}, {72, 1.14, 529.69}, {68, 1.87, 398.15},
    {67, 4.41, 5507.55}, {59, 2.89, 5223.69}, {56, 2.17, 155.42},
    {45, 0.4, 796.3}, {36, 0.47, 775.52}, {29, 2.65, 7.11},
    {21, 5.34, 0.98}, {19, 1.85, 5486.78}, {19, 4.97, 213.3},
    {17, 2.99, 6275.96}, {16, 0.03, 2544.31}, {16, 1.43, 2146.17},
    {15, 1.21, 10977.08}, {12, 2.83, 1748.02}, {12, 3.26, 5088.63},
    {12, 5.27, 1194.45}, {12, 2.08, 4694}, {11, 0.77, 553.57},
    {10, 1.3, 6286.6}, {10, 4.24, 1349.87}, {9, 2.7, 242.73},
    {9, 5.64, 951.72}, {8, 5.3, 2352.87}, {6, 2.65, 9437.76},
    {6, 4.67, 4690.48},
};
constexpr Term kL2[] = {
    {52919.0, 0, 0}, {8720.0, 1.0721, 6283.0758}, {309.0, 0.867, 12566.152},
    {27, 0.05, 3.52}, {16, 5.19, 26.3}, {16, 3.68, 155.42},
    {10, 0.76, 18849.23}, {9, 2.06, 77713.77}, {7, 0.83, 775.52},
    {5, 4.66, 1577.34}, {4, 1.03, 7.11}, {4, 3.44, 5573.14},
    {3, 5.14, 796.3}, {3, 6.05, 5507.55}, {3, 1.19, 242.73},
    {3, 6.12, 529.69}, {3, 0.31, 398.15}, {3, 2.28, 553.57},
    {2, 4.38, 5223.69}, {2, 3.75, 0.98},
};
constexpr Term kL3[] = {
    {289.0, 5.844, 6283.076}, {35, 0, 0}, {17, 5.49, 12566.15}, {3, 5.2, 155.42},
    {1, 4.72, 3.52}, {1, 5.3, 18849.23}, {1, 5.97, 242.73},
};
constexpr Term kL4[] = {{114.0, 3.142, 0}, {8, 4.13, 6283.08}, {1, 3.84, 12566.15}};
constexpr Term kL5[] = {{1, 3.14, 0}};

constexpr Term kB0[] = {
    {280.0, 3.199, 84334.662}, {102.0, 5.422, 5507.553}, {80, 3.88, 5223.69},
    {44, 3.7, 2352.87}, {32, 4, 1577.34},
};
constexpr Term kB1[] = {{9, 3.9, 5507.55}, {6, 1.73, 5223.69}};

constexpr Term kR0[] = {
    {100013989.0, 0, 0}, {1670700.0, 3.0984635, 6283.07585}, {13956.0, 3.05525, 12566.1517},
    {3084.0, 5.1985, 77713.7715}, {1628.0, 1.1739, 5753.3849}, {1576.0, 2.8469, 7860.4194},
    {925.0, 5.453, 11506.77}, {542.0, 4.564, 3930.21}, {472.0, 3.661, 5884.927},
    {346.0, 0.964, 5507.553}, {329.0, 5.9, 5223.694}, {307.0, 0.299, 5573.143},
    {243.0, 4.273, 11790.629}, {212.0, 5.847, 1577.344}, {186.0, 5.022, 10977.079},
    {175.0, 3.012, 18849.228}, {110.0, 5.055, 5486.778}, {98, 0.89, 6069.78},
    {86, 5.69, 15720.84}, {86, 1.27, 161000.69}, {65, 0.27, 17260.15},
    {63, 0.92, 529.69}, {57, 2.01, 83996.85}, {56, 5.24, 71430.7},
    {49, 3.25, 2544.31}, {47, 2.58, 775.52}, {45, 5.54, 9437.76},
    {43, 6.01, 6275.96}, {39, 5.36, 4694}, {38, 2.39, 8827.39},
    {37, 0.83, 19651.05}, {37, 4.9, 12139.55}, {36, 1.67, 12036.46},
    {35, 1.84, 2942.46}, {33, 0.24, 7084.9}, {32, 0.18, 5088.63},
    {32, 1.78, 398.15}, {28, 1.21, 6286.6}, {28, 1.9, 6279.55},
    {26, 4.59, 10447.39},
};
constexpr Term kR1[] = {
    {103019.0, 1.10749, 6283.07585}, {1721.0, 1.0644, 12566.1517}, {702.0, 3.142, 0},
    {32, 1.02, 18849.23}, {31, 2.84, 5507.55}, {25, 1.32, 5223.69},
    {18, 1.42, 1577.34}, {10, 5.91, 10977.08}, {9, 1.42, 6275.96},
    {9, 0.27, 5486.78},
};
constexpr Term kR2[] = {
    {4359.0, 5.7846, 6283.0758}, {124.0, 5.579, 12566.152}, {12, 3.14, 0},
    {9, 3.63, 77713.77}, {6, 1.87, 5573.14}, {3, 5.47, 18849.23},
};
constexpr Term kR3[] = {{145.0, 4.273, 6283.076}, {7, 3.92, 12566.15}};
constexpr Term kR4[] = {{4, 2.56, 6283.08}};

struct Series {
  const Term* terms;
  int count;
};
template <int N>
constexpr Series S(const Term (&t)[N]) {
  return {t, N};
}

// Equation (9)-(10): sum_i (sum_k A cos(B + C JME)) * JME^i / 1e8.
template <int N>
double EarthValue(const Series (&series)[N], double jme) {
  double total = 0.0, power = 1.0;
  for (const Series& s : series) {
    double sum = 0.0;
    for (int k = 0; k < s.count; ++k) sum += s.terms[k].a * std::cos(s.terms[k].b + s.terms[k].c * jme);
    total += sum * power;
    power *= jme;
  }
  return total / 1e8;
}

// ---- Table A4.3: nutation in longitude and obliquity. ----
// Multiples of X0 (mean elongation of the Moon from the Sun), X1 (mean anomaly of the Sun),
// X2 (mean anomaly of the Moon), X3 (Moon's argument of latitude), X4 (longitude of the
// Moon's ascending node); coefficients a, b (delta psi) and c, d (delta epsilon), 0.0001".
struct NutationTerm {
  signed char y[5];
  double a, b, c, d;
};

constexpr NutationTerm kNutation[] = {
    {{0, 0, 0, 0, 1}, -171996, -174.2, 92025, 8.9},
    {{-2, 0, 0, 2, 2}, -13187, -1.6, 5736, -3.1},
    {{0, 0, 0, 2, 2}, -2274, -0.2, 977, -0.5},
    {{0, 0, 0, 0, 2}, 2062, 0.2, -895, 0.5},
    {{0, 1, 0, 0, 0}, 1426, -3.4, 54, -0.1},
    {{0, 0, 1, 0, 0}, 712, 0.1, -7, 0},
    {{-2, 1, 0, 2, 2}, -517, 1.2, 224, -0.6},
    {{0, 0, 0, 2, 1}, -386, -0.4, 200, 0},
    {{0, 0, 1, 2, 2}, -301, 0, 129, -0.1},
    {{-2, -1, 0, 2, 2}, 217, -0.5, -95, 0.3},
    {{-2, 0, 1, 0, 0}, -158, 0, 0, 0},
    {{-2, 0, 0, 2, 1}, 129, 0.1, -70, 0},
    {{0, 0, -1, 2, 2}, 123, 0, -53, 0},
    {{2, 0, 0, 0, 0}, 63, 0, 0, 0},
    {{0, 0, 1, 0, 1}, 63, 0.1, -33, 0},
    {{2, 0, -1, 2, 2}, -59, 0, 26, 0},
    {{0, 0, -1, 0, 1}, -58, -0.1, 32, 0},
    {{0, 0, 1, 2, 1}, -51, 0, 27, 0},
    {{-2, 0, 2, 0, 0}, 48, 0, 0, 0},
    {{0, 0, -2, 2, 1}, 46, 0, -24, 0},
    {{2, 0, 0, 2, 2}, -38, 0, 16, 0},
    {{0, 0, 2, 2, 2}, -31, 0, 13, 0},
    {{0, 0, 2, 0, 0}, 29, 0, 0, 0},
    {{-2, 0, 1, 2, 2}, 29, 0, -12, 0},
    {{0, 0, 0, 2, 0}, 26, 0, 0, 0},
    {{-2, 0, 0, 2, 0}, -22, 0, 0, 0},
    {{0, 0, -1, 2, 1}, 21, 0, -10, 0},
    {{0, 2, 0, 0, 0}, 17, -0.1, 0, 0},
    {{2, 0, -1, 0, 1}, 16, 0, -8, 0},
    {{-2, 2, 0, 2, 2}, -16, 0.1, 7, 0},
    {{0, 1, 0, 0, 1}, -15, 0, 9, 0},
    {{-2, 0, 1, 0, 1}, -13, 0, 7, 0},
    {{0, -1, 0, 0, 1}, -12, 0, 6, 0},
    {{0, 0, 2, -2, 0}, 11, 0, 0, 0},
    {{2, 0, -1, 2, 1}, -10, 0, 5, 0},
    {{2, 0, 1, 2, 2}, -8, 0, 3, 0},
    {{0, 1, 0, 2, 2}, 7, 0, -3, 0},
    {{-2, 1, 1, 0, 0}, -7, 0, 0, 0},
    {{0, -1, 0, 2, 2}, -7, 0, 3, 0},
    {{2, 0, 0, 2, 1}, -7, 0, 3, 0},
    {{2, 0, 1, 0, 0}, 6, 0, 0, 0},
    {{-2, 0, 2, 2, 2}, 6, 0, -3, 0},
    {{-2, 0, 1, 2, 1}, 6, 0, -3, 0},
    {{2, 0, -2, 0, 1}, -6, 0, 3, 0},
    {{2, 0, 0, 0, 1}, -6, 0, 3, 0},
    {{0, -1, 1, 0, 0}, 5, 0, 0, 0},
    {{-2, -1, 0, 2, 1}, -5, 0, 3, 0},
    {{-2, 0, 0, 0, 1}, -5, 0, 3, 0},
    {{0, 0, 2, 2, 1}, -5, 0, 3, 0},
    {{-2, 0, 2, 0, 1}, 4, 0, 0, 0},
    {{-2, 1, 0, 2, 1}, 4, 0, 0, 0},
    {{0, 0, 1, -2, 0}, 4, 0, 0, 0},
    {{-1, 0, 1, 0, 0}, -4, 0, 0, 0},
    {{-2, 1, 0, 0, 0}, -4, 0, 0, 0},
    {{1, 0, 0, 0, 0}, -4, 0, 0, 0},
    {{0, 0, 1, 2, 0}, 3, 0, 0, 0},
    {{0, 0, -2, 2, 2}, -3, 0, 0, 0},
    {{-1, -1, 1, 0, 0}, -3, 0, 0, 0},
    {{0, 1, 1, 0, 0}, -3, 0, 0, 0},
    {{0, -1, 1, 2, 2}, -3, 0, 0, 0},
    {{2, -1, -1, 2, 2}, -3, 0, 0, 0},
    {{0, 0, 3, 2, 2}, -3, 0, 0, 0},
    {{2, -1, 0, 2, 2}, -3, 0, 0, 0},
};
static_assert(sizeof(kNutation) / sizeof(kNutation[0]) == 63, "table A4.3 has 63 rows");

// a + b x + c x^2 + d x^3.
double Cubic(double a, double b, double c, double d, double x) { return ((d * x + c) * x + b) * x + a; }

// 3.1: Julian day (UT) of a calendar date and time; `day_fraction_hours` may run outside
// [0, 24) (the UTC offset is folded in), the formula is linear in it.
double JulianDay(int year, int month, int day, double day_hours) {
  if (month < 3) {
    year -= 1;
    month += 12;
  }
  // INT() of the paper truncates toward zero; year + 4716 > 0 over the validity range.
  double jd = std::trunc(365.25 * (year + 4716.0)) + std::trunc(30.6001 * (month + 1)) + day + day_hours / 24.0 - 1524.5;
  if (jd > 2299160.0) {  // Gregorian calendar from 1582-10-15
    const double a = std::trunc(year / 100.0);
    jd += 2.0 - a + std::trunc(a / 4.0);
  }
  return jd;
}

bool IsLeapYear(int year) {
  if (year <= 1582) return year % 4 == 0;  // Julian calendar (astronomical years: 0, -4, ... are leap)
  return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
}

int DaysInMonth(int year, int month) {
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return month == 2 && IsLeapYear(year) ? 29 : kDays[month - 1];
}

std::string Num(double v) {
  std::ostringstream ss;
  ss.precision(10);
  ss << v;
  return ss.str();
}

}  // namespace

bool SpaInput::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    *why = m;
    return false;
  };
  if (year < -2000 || year > 6000) {
    return fail("year " + std::to_string(year) + ": the SPA is valid for years -2000..6000");
  }
  if (month < 1 || month > 12) return fail("month " + std::to_string(month) + ": expected 1..12");
  if (day < 1 || day > DaysInMonth(year, month)) {
    return fail("day " + std::to_string(day) + ": expected 1.." + std::to_string(DaysInMonth(year, month)) + " for " +
                std::to_string(year) + "-" + (month < 10 ? "0" : "") + std::to_string(month));
  }
  if (year == 1582 && month == 10 && day > 4 && day < 15) {
    return fail("day 1582-10-" + std::to_string(day) + ": does not exist (Julian 1582-10-04 is followed by Gregorian 1582-10-15)");
  }
  if (hour < 0 || hour > 24) return fail("hour " + std::to_string(hour) + ": expected 0..24");
  if (minute < 0 || minute > 59) return fail("minute " + std::to_string(minute) + ": expected 0..59");
  if (!(second >= 0.0 && second < 60.0)) return fail("second " + Num(second) + ": expected [0, 60)");
  if (hour == 24 && (minute > 0 || second > 0.0)) return fail("hour 24: only 24:00:00 is allowed");
  if (!(std::abs(timezone_h) <= 18.0)) return fail("timezone " + Num(timezone_h) + " h: expected a UTC offset in [-18, 18] hours");
  if (!(std::abs(delta_ut1_s) < 1.0)) return fail("delta_ut1 " + Num(delta_ut1_s) + " s: expected (-1, 1) seconds");
  if (!(std::abs(delta_t_s) <= 8000.0)) return fail("delta_t " + Num(delta_t_s) + " s: expected |delta T| <= 8000 seconds");
  if (std::isnan(latitude_deg)) return fail("latitude: required (degrees, north positive)");
  if (!(std::abs(latitude_deg) <= 90.0)) return fail("latitude " + Num(latitude_deg) + ": expected degrees in [-90, 90]");
  if (std::isnan(longitude_deg)) return fail("longitude: required (degrees, east positive)");
  if (!(std::abs(longitude_deg) <= 180.0)) {
    return fail("longitude " + Num(longitude_deg) + ": expected degrees in [-180, 180] (east positive)");
  }
  if (!(elevation_m >= -6500000.0 && std::isfinite(elevation_m))) {
    return fail("elevation " + Num(elevation_m) + " m: expected metres above sea level, >= -6500000");
  }
  if (!(pressure_mbar >= 0.0 && pressure_mbar <= 5000.0)) {
    return fail("pressure " + Num(pressure_mbar) + " mbar: expected [0, 5000] millibars");
  }
  if (!(temperature_c > -273.0 && temperature_c <= 6000.0)) {
    return fail("temperature " + Num(temperature_c) + " C: expected (-273, 6000] degrees Celsius");
  }
  if (!(std::abs(atmospheric_refraction_deg) <= 5.0)) {
    return fail("atmospheric_refraction " + Num(atmospheric_refraction_deg) + ": expected |degrees| <= 5");
  }
  if (!(std::abs(slope_deg) <= 360.0)) return fail("slope " + Num(slope_deg) + ": expected |degrees| <= 360");
  if (!(std::abs(azimuth_rotation_deg) <= 360.0)) {
    return fail("azimuth_rotation " + Num(azimuth_rotation_deg) + ": expected |degrees| <= 360");
  }
  return true;
}

SpaResult ComputeSolarPosition(const SpaInput& in) {
  std::string why;
  if (!in.IsValid(&why)) throw Error("solar position: " + why);
  SpaResult r;

  // 3.1 Julian and Julian ephemeris day, century, millennium.
  const double ut_hours = in.hour - in.timezone_h + (in.minute + (in.second + in.delta_ut1_s) / 60.0) / 60.0;
  const double jd = JulianDay(in.year, in.month, in.day, ut_hours);
  const double jde = jd + in.delta_t_s / 86400.0;
  const double jc = (jd - 2451545.0) / 36525.0;
  const double jce = (jde - 2451545.0) / 36525.0;
  const double jme = jce / 10.0;
  r.julian_day = jd;
  r.julian_ephemeris_day = jde;

  // 3.2 Earth heliocentric longitude L, latitude B (degrees) and radius vector R (AU).
  static constexpr Series kL[] = {S(kL0), S(kL1), S(kL2), S(kL3), S(kL4), S(kL5)};
  static constexpr Series kB[] = {S(kB0), S(kB1)};
  static constexpr Series kR[] = {S(kR0), S(kR1), S(kR2), S(kR3), S(kR4)};
  const double L = Wrap360(Deg(EarthValue(kL, jme)));
  const double B = Deg(EarthValue(kB, jme));
  const double R = EarthValue(kR, jme);
  r.heliocentric_longitude_deg = L;
  r.heliocentric_latitude_deg = B;
  r.radius_au = R;

  // 3.3 Geocentric longitude and latitude.
  const double theta = Wrap360(L + 180.0);
  const double beta = -B;
  r.geocentric_longitude_deg = theta;
  r.geocentric_latitude_deg = beta;

  // 3.4 Nutation in longitude and obliquity.
  const double x[5] = {
      Cubic(297.85036, 445267.111480, -0.0019142, 1.0 / 189474.0, jce),    // X0
      Cubic(357.52772, 35999.050340, -0.0001603, -1.0 / 300000.0, jce),    // X1
      Cubic(134.96298, 477198.867398, 0.0086972, 1.0 / 56250.0, jce),     // X2
      Cubic(93.27191, 483202.017538, -0.0036825, 1.0 / 327270.0, jce),     // X3
      Cubic(125.04452, -1934.136261, 0.0020708, 1.0 / 450000.0, jce),      // X4
  };
  double sum_psi = 0.0, sum_eps = 0.0;
  for (const NutationTerm& t : kNutation) {
    double arg = 0.0;
    for (int j = 0; j < 5; ++j) arg += x[j] * t.y[j];
    arg = Rad(arg);
    sum_psi += (t.a + t.b * jce) * std::sin(arg);
    sum_eps += (t.c + t.d * jce) * std::cos(arg);
  }
  const double dpsi = sum_psi / 36000000.0;  // 0.0001 arcsec -> degrees
  const double deps = sum_eps / 36000000.0;
  r.nutation_longitude_deg = dpsi;
  r.nutation_obliquity_deg = deps;

  // 3.5 True obliquity of the ecliptic (mean obliquity in arcsec, U = JME / 10).
  const double u = jme / 10.0;
  static constexpr double kEps0[] = {84381.448, -4680.93, -1.55, 1999.25, -51.38, -249.67, -39.05, 7.12, 27.87, 5.79, 2.45};
  double eps0 = 0.0;
  for (int k = 10; k >= 0; --k) eps0 = eps0 * u + kEps0[k];
  const double eps = eps0 / 3600.0 + deps;
  r.true_obliquity_deg = eps;

  // 3.6 Aberration correction; 3.7 apparent sun longitude.
  const double dtau = -20.4898 / (3600.0 * R);
  const double lambda = theta + dpsi + dtau;
  r.aberration_deg = dtau;
  r.apparent_longitude_deg = lambda;

  // 3.8 Apparent sidereal time at Greenwich.
  const double nu0 = Wrap360(280.46061837 + 360.98564736629 * (jd - 2451545.0) + jc * jc * (0.000387933 - jc / 38710000.0));
  const double nu = nu0 + dpsi * std::cos(Rad(eps));
  r.sidereal_time_deg = nu;

  // 3.9-3.10 Geocentric right ascension and declination.
  const double sl = std::sin(Rad(lambda)), ce = std::cos(Rad(eps)), se = std::sin(Rad(eps));
  const double alpha = Wrap360(Deg(std::atan2(sl * ce - std::tan(Rad(beta)) * se, std::cos(Rad(lambda)))));
  const double delta = Deg(std::asin(std::sin(Rad(beta)) * ce + std::cos(Rad(beta)) * se * sl));
  r.right_ascension_deg = alpha;
  r.declination_deg = delta;

  // 3.11 Observer local hour angle (longitude east positive).
  const double H = Wrap360(nu + in.longitude_deg - alpha);
  r.hour_angle_deg = H;

  // 3.12 Topocentric right ascension and declination (parallax).
  const double xi = Rad(8.794 / (3600.0 * R));  // equatorial horizontal parallax
  const double phi = Rad(in.latitude_deg);
  const double u_lat = std::atan(0.99664719 * std::tan(phi));
  const double xx = std::cos(u_lat) + in.elevation_m / 6378140.0 * std::cos(phi);
  const double yy = 0.99664719 * std::sin(u_lat) + in.elevation_m / 6378140.0 * std::sin(phi);
  const double Hr = Rad(H), dr = Rad(delta);
  const double denom = std::cos(dr) - xx * std::sin(xi) * std::cos(Hr);
  const double dalpha = std::atan2(-xx * std::sin(xi) * std::sin(Hr), denom);
  const double delta_p = std::atan2((std::sin(dr) - yy * std::sin(xi)) * std::cos(dalpha), denom);
  r.right_ascension_topo_deg = alpha + Deg(dalpha);
  r.declination_topo_deg = Deg(delta_p);

  // 3.13 Topocentric local hour angle.
  const double Hp = Hr - dalpha;
  r.hour_angle_topo_deg = Deg(Hp);

  // 3.14 Topocentric zenith angle: geometric elevation, refraction (Bennett's formula as in
  // the paper; applied while the sun's upper limb can still be refracted above the horizon,
  // as in NREL's reference implementation: below that it is 0 and the formula is singular).
  const double e0 = Deg(std::asin(std::sin(phi) * std::sin(delta_p) + std::cos(phi) * std::cos(delta_p) * std::cos(Hp)));
  double de = 0.0;
  if (e0 >= -(kSunRadiusDeg + in.atmospheric_refraction_deg)) {
    de = in.pressure_mbar / 1010.0 * 283.0 / (273.0 + in.temperature_c) * 1.02 / (60.0 * std::tan(Rad(e0 + 10.3 / (e0 + 5.11))));
  }
  const double e = e0 + de;
  r.elevation_no_refraction_deg = e0;
  r.refraction_deg = de;
  r.elevation_deg = e;
  r.zenith_deg = 90.0 - e;

  // 3.15 Topocentric azimuth: astronomers' (from south, westward), then navigators' (from north, eastward).
  const double gamma = Wrap360(Deg(std::atan2(std::sin(Hp), std::cos(Hp) * std::sin(phi) - std::tan(delta_p) * std::cos(phi))));
  r.azimuth_astro_deg = gamma;
  r.azimuth_deg = Wrap360(gamma + 180.0);

  // 3.16 Incidence angle on a surface of slope omega and azimuth rotation gamma_s.
  const double z = Rad(r.zenith_deg), w = Rad(in.slope_deg);
  const double cos_i = std::cos(z) * std::cos(w) + std::sin(w) * std::sin(z) * std::cos(Rad(gamma - in.azimuth_rotation_deg));
  r.incidence_deg = Deg(std::acos(std::fmax(-1.0, std::fmin(1.0, cos_i))));

  // Appendix A.1: equation of time from the sun's mean longitude M, in minutes (|E| <= 20).
  const double M = Wrap360(280.4664567 + jme * (360007.6982779 + jme * (0.03032028 + jme * (1.0 / 49931.0 +
                                                                       jme * (-1.0 / 15300.0 + jme * (-1.0 / 2000000.0))))));
  double eot = 4.0 * (M - 0.0057183 - alpha + dpsi * std::cos(Rad(eps)));
  if (eot < -20.0) eot += 1440.0;
  if (eot > 20.0) eot -= 1440.0;
  r.equation_of_time_min = eot;
  return r;
}

namespace {

// A cursor over an ISO 8601 text; errors name `what`, the text and the expected form.
struct Iso8601Reader {
  const std::string& text;
  std::string head;
  size_t pos = 0;

  Error Fail(const std::string& m) const {
    return Error(head + m + " (expected ISO 8601 YYYY-MM-DDThh:mm[:ss[.fff]] with Z or +hh:mm/-hh:mm, e.g. 2003-10-17T12:30:30-07:00)");
  }
  // Reads exactly `n` digits (or at least n when `at_least`) as an integer.
  int Digits(int n, const char* field, bool at_least = false) {
    size_t start = pos;
    while (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos])) &&
           (at_least || static_cast<int>(pos - start) < n)) {
      ++pos;
    }
    const int got = static_cast<int>(pos - start);
    if (got < n || (!at_least && got != n)) throw Fail(std::string(field) + ": expected " + std::to_string(n) + " digits");
    if (got > 9) throw Fail(std::string(field) + ": too many digits");
    return std::atoi(text.substr(start, got).c_str());
  }
  void Expect(char c, const char* where) {
    if (pos >= text.size() || text[pos] != c) throw Fail(std::string("expected '") + c + "' " + where);
    ++pos;
  }
};

// Optional ":ss[.fff]" (a comma as decimal mark too); 0 when absent.
double ReadIsoSeconds(Iso8601Reader& r) {
  const std::string& text = r.text;
  if (!(r.pos < text.size() && text[r.pos] == ':')) return 0.0;
  ++r.pos;
  const size_t start = r.pos;
  r.Digits(2, "second");
  if (r.pos < text.size() && (text[r.pos] == '.' || text[r.pos] == ',')) {
    ++r.pos;
    const size_t frac = r.pos;
    while (r.pos < text.size() && std::isdigit(static_cast<unsigned char>(text[r.pos]))) ++r.pos;
    if (r.pos == frac) throw r.Fail("second: expected digits after the decimal mark");
  }
  std::string s = text.substr(start, r.pos - start);
  for (char& c : s)
    if (c == ',') c = '.';
  return std::strtod(s.c_str(), nullptr);
}

// UTC offset in hours: required (a local time without one is ambiguous).
double ReadIsoUtcOffset(Iso8601Reader& r) {
  const std::string& text = r.text;
  if (r.pos >= text.size()) throw r.Fail("timezone: missing UTC offset (append Z for UTC or +hh:mm/-hh:mm)");
  if (text[r.pos] == 'Z' || text[r.pos] == 'z') {
    ++r.pos;
    return 0.0;
  }
  if (text[r.pos] == '+' || text[r.pos] == '-') {
    const double s = text[r.pos++] == '-' ? -1.0 : 1.0;
    const int oh = r.Digits(2, "timezone hours");
    int om = 0;
    if (r.pos < text.size() && text[r.pos] == ':') {
      ++r.pos;
      om = r.Digits(2, "timezone minutes");
    } else if (r.pos < text.size()) {
      om = r.Digits(2, "timezone minutes");
    }
    if (om > 59) throw r.Fail("timezone minutes " + std::to_string(om) + ": expected 00..59");
    return s * (oh + om / 60.0);
  }
  throw r.Fail("timezone: expected Z or +hh:mm/-hh:mm after the time, got '" + text.substr(r.pos) + "'");
}

}  // namespace

SpaInput ParseIso8601(const std::string& text, const std::string& what) {
  Iso8601Reader r{text, what + " '" + text + "': "};
  SpaInput in;
  int sign = 1;
  if (r.pos < text.size() && (text[r.pos] == '+' || text[r.pos] == '-')) sign = text[r.pos++] == '-' ? -1 : 1;
  in.year = sign * r.Digits(4, "year", true);
  r.Expect('-', "after the year");
  in.month = r.Digits(2, "month");
  r.Expect('-', "after the month");
  in.day = r.Digits(2, "day");
  if (r.pos >= text.size() || (text[r.pos] != 'T' && text[r.pos] != 't' && text[r.pos] != ' ')) {
    throw r.Fail("expected 'T' and a time of day after the date");
  }
  ++r.pos;
  in.hour = r.Digits(2, "hour");
  r.Expect(':', "after the hour");
  in.minute = r.Digits(2, "minute");
  in.second = ReadIsoSeconds(r);
  in.timezone_h = ReadIsoUtcOffset(r);
  if (r.pos != text.size()) throw r.Fail("unexpected trailing text '" + text.substr(r.pos) + "'");

  // Ranges (the calendar fields; latitude and longitude are not part of the time).
  SpaInput probe = in;
  probe.latitude_deg = 0.0;
  probe.longitude_deg = 0.0;
  std::string why;
  if (!probe.IsValid(&why)) throw Error(r.head + why);
  return in;
}

double LatLongLongitudeOfAzimuthDeg(double azimuth_deg, double north_longitude_deg) {
  double lon = std::fmod(north_longitude_deg - azimuth_deg, 360.0);
  if (lon <= -180.0) lon += 360.0;
  if (lon > 180.0) lon -= 360.0;
  return lon;
}

std::array<double, 3> SunDirectionInFrame(const SpaResult& sun, double north_longitude_deg) {
  return latlong::DirectionFromElevationAzimuthDeg(90.0 - sun.zenith_deg,
                                                   LatLongLongitudeOfAzimuthDeg(sun.azimuth_deg, north_longitude_deg));
}

}  // namespace skycal::capture
