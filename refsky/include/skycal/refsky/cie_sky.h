// The 15 CIE standard general skies (CIE S 011/E:2003 = ISO 15469:2004, "Spatial
// distribution of daylight - CIE standard general sky"), used by the CIE benchmark and tests as references
// independent of the game's sky model (docs/benchmarks.md, "How measurements are taken").
//
// Relative luminance of a sky element (dimensionless, 1 at the zenith):
//   L / Lz = f(chi) phi(Z) / (f(Zs) phi(0))
//   phi(Z)   = 1 + a exp(b / cos Z)                  gradation (0 <= Z <= pi/2)
//   phi(0)   = 1 + a exp(b)
//   f(chi)   = 1 + c (exp(d chi) - exp(d pi/2)) + e cos^2 chi     scattering indicatrix
// Z = zenith angle of the view direction, Zs = zenith angle of the sun, chi = angle between
// view and sun (all radians). At the zenith chi = Zs, hence L/Lz = 1 there for every type.
// At the horizon (Z = pi/2) cos Z = 0 and, since every standard type has b < 0,
// b / cos Z -> -inf and phi(pi/2) = 1 exactly (the limit; evaluated explicitly, not as
// exp(b / 0)).
// Parameters a-e per type: datasets/tables/cie_general_sky.csv (from the standard's
// table 1 / table 2 grouping), read at run time.
#pragma once
#include <array>
#include <string>
#include <vector>

namespace skycal::refsky {

struct CieSkyType {
  int type = 0;                  // 1 .. 15
  std::string gradation_group;   // I .. VI (a, b)
  std::string indicatrix_group;  // 1 .. 6 (c, d, e)
  double a = 0, b = 0, c = 0, d = 0, e = 0;  // dimensionless; b, d multiply 1/cos Z and chi (rad)
  std::string description;
};

// Path of the bundled table: DataPath("datasets/tables/cie_general_sky.csv") (core/data_dir.h).
std::string DefaultCieCsvPath();

// Reads the table (header sky_type,gradation_group,indicatrix_group,a,b,c,d,e,description;
// quoted fields may hold commas). Throws skycal::Error naming the file (and line) when it
// is missing, malformed, or a type has b >= 0 (phi would not tend to 1 at the horizon).
std::vector<CieSkyType> LoadCieSkyTypes(const std::string& csv_path);

// phi from cos Z (view zenith cosine = sin of elevation); cos Z <= 0 (horizon and below)
// returns the horizon limit 1.
double CieGradation(const CieSkyType& s, double cos_zenith);
// f(chi), chi in radians.
double CieIndicatrix(const CieSkyType& s, double chi_rad);
// L/Lz from angles (radians): view zenith Z in [0, pi/2], sun zenith Zs in [0, pi/2],
// chi in [0, pi].
double CieRelativeLuminance(const CieSkyType& s, double view_zenith_rad, double sun_zenith_rad, double chi_rad);
// L/Lz from unit vectors in the lat-long frame (+Y up, core/latlong.h). Views below the
// horizon (y < 0) are outside the model's domain: the caller decides (the CIE benchmark and tests writes 0).
double CieRelativeLuminance(const CieSkyType& s, const std::array<double, 3>& view, const std::array<double, 3>& sun);

}  // namespace skycal::refsky
