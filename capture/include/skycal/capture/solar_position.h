// The sun's position for a place and time: NREL's Solar Position Algorithm (SPA),
// I. Reda and A. Andreas, "Solar position algorithm for solar radiation applications",
// Solar Energy 76(5), 577-589, 2004 (NREL/TP-560-34302, revised 2008). Uncertainty
// +/-0.0003 deg for years -2000..6000 (the algorithm's validity range; outside it the
// input is refused). Section numbers in solar_position.cc follow the paper's section 3.
//
// Time: the civil time of the place plus its offset from UTC (timezone_h, hours, east
// positive: -7 for MST). As in the SPA (and Meeus), dates before 1582-10-15 are Julian
// calendar dates, later ones Gregorian; years are astronomical (0 = 1 BC, -1 = 2 BC).
// ISO 8601 strings go through ParseIso8601 (same calendar rule).
//
// Angles in degrees; longitude east positive, latitude north positive (geodetic, WGS-84
// close enough: the SPA's Earth flattening is 1/298.257).
#pragma once
#include <array>
#include <limits>
#include <string>

namespace skycal::capture {

struct SpaInput {
  int year = 2000, month = 1, day = 1, hour = 0, minute = 0;
  double second = 0.0;
  double timezone_h = 0.0;     // UTC offset of the local time above, hours in [-18, 18]
  double delta_ut1_s = 0.0;    // UT1 - UTC, seconds in (-1, 1) (IERS Bulletin A; 0 is fine at 1 s)
  double delta_t_s = 67.0;     // TT - UT1, seconds (67 s in 2003, ~69 s in the 2020s), |.| <= 8000
  double latitude_deg = std::numeric_limits<double>::quiet_NaN();   // [-90, 90], required
  double longitude_deg = std::numeric_limits<double>::quiet_NaN();  // [-180, 180], east positive, required
  double elevation_m = 0.0;             // observer height above sea level, >= -6500000
  double pressure_mbar = 1013.25;       // annual mean local pressure, [0, 5000] (refraction)
  double temperature_c = 15.0;          // annual mean local temperature, (-273, 6000] (refraction)
  double atmospheric_refraction_deg = 0.5667;  // refraction at sunrise/sunset, |.| <= 5
  double slope_deg = 0.0;               // surface tilt from horizontal, for incidence_deg, |.| <= 360
  double azimuth_rotation_deg = 0.0;    // surface azimuth, from south, westward positive, |.| <= 360

  // False (and the field at fault with what was expected in *why) for out-of-range input.
  bool IsValid(std::string* why) const;
};

struct SpaResult {
  // Topocentric, for the observer; zenith and elevation include atmospheric refraction.
  double zenith_deg = 0.0;         // 0 at the zenith, 90 at the (refracted) horizon
  double elevation_deg = 0.0;      // 90 - zenith_deg
  double azimuth_deg = 0.0;        // from north, eastward (clockwise seen from above), [0, 360)
  double azimuth_astro_deg = 0.0;  // from south, westward (astronomers' convention), [0, 360)
  double incidence_deg = 0.0;      // on the surface given by slope_deg/azimuth_rotation_deg
  double elevation_no_refraction_deg = 0.0;  // e0, the geometric topocentric elevation
  double refraction_deg = 0.0;               // delta e added to e0 (0 well below the horizon)
  double right_ascension_topo_deg = 0.0;     // alpha'
  double declination_topo_deg = 0.0;         // delta'
  double hour_angle_topo_deg = 0.0;          // H'

  // Intermediate values (the paper's table A5.1 lists them for its example).
  double julian_day = 0.0;                 // JD (UT)
  double julian_ephemeris_day = 0.0;       // JDE (TT)
  double heliocentric_longitude_deg = 0.0;  // L, [0, 360)
  double heliocentric_latitude_deg = 0.0;   // B
  double radius_au = 0.0;                   // R, Earth-Sun distance
  double geocentric_longitude_deg = 0.0;    // Theta
  double geocentric_latitude_deg = 0.0;     // beta
  double nutation_longitude_deg = 0.0;      // delta psi
  double nutation_obliquity_deg = 0.0;      // delta epsilon
  double true_obliquity_deg = 0.0;          // epsilon
  double aberration_deg = 0.0;              // delta tau
  double apparent_longitude_deg = 0.0;      // lambda
  double sidereal_time_deg = 0.0;           // nu, apparent sidereal time at Greenwich
  double right_ascension_deg = 0.0;         // alpha (geocentric), [0, 360)
  double declination_deg = 0.0;             // delta (geocentric)
  double hour_angle_deg = 0.0;              // H (geocentric), [0, 360)
  double equation_of_time_min = 0.0;        // apparent minus mean solar time, minutes
};

// The full SPA; throws skycal::Error (naming the field) when !input.IsValid().
SpaResult ComputeSolarPosition(const SpaInput& input);

// ISO 8601 date and time with a UTC offset, into the time fields of a SpaInput (the other
// fields keep their defaults). Accepted: YYYY-MM-DDThh:mm[:ss[.fff]] followed by Z, +hh:mm,
// -hh:mm, +hhmm or +hh; a space may replace the T; years may carry a sign and more digits
// (-0500-03-01T..., +10000 is refused later by the range check). A missing offset, a field
// out of range (month 13, day 31 in April, 25:00) or trailing text throws skycal::Error
// naming `what` (e.g. "CaptureOptions::time_iso") and the field.
SpaInput ParseIso8601(const std::string& text, const std::string& what = "time");

// Unit vector toward the sun in the project's lat-long frame (core/latlong.h: +Y up,
// longitude 0 -> +Z, longitude +90 -> +X), for a frame whose geographic north lies at
// lat-long longitude `north_longitude_deg` (a camera heading of 0 puts north at +Z).
// Convention: the frame is the real, unmirrored sky seen from inside (right-handed, +Y up),
// so with north at +Z east is -X (longitude -90): compass azimuth A (from north, eastward)
// maps to lat-long longitude
//     longitude = north_longitude_deg - A,   latitude = elevation = 90 - zenith_deg.
// In the lat-long image (longitude decreasing left to right) east lies to the right of
// north, as for an observer facing north. The refracted (apparent) elevation is used.
std::array<double, 3> SunDirectionInFrame(const SpaResult& sun, double north_longitude_deg);

// The lat-long longitude (degrees, in (-180, 180]) of compass azimuth `azimuth_deg` for a
// frame with north at `north_longitude_deg` (the mapping above).
double LatLongLongitudeOfAzimuthDeg(double azimuth_deg, double north_longitude_deg);

}  // namespace skycal::capture
