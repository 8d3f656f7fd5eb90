#include "sun_verb.h"

#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>

#include "command_line.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

std::string Num(double v, int precision = 10) {
  std::ostringstream ss;
  ss.precision(precision);
  ss << v;
  return ss.str();
}

}  // namespace

bool SunOptions::IsValid(std::string* why) const {
  if (time.empty()) {
    *why = "--time ISO8601 is required (e.g. 2003-10-17T12:30:30-07:00)";
    return false;
  }
  try {
    capture::ParseIso8601(time, "--time");
  } catch (const Error& e) {
    *why = e.what();
    return false;
  }
  if (!latitude_deg) {
    *why = "--lat DEG is required (degrees, north positive)";
    return false;
  }
  if (!(std::abs(*latitude_deg) <= 90.0)) {
    *why = "--lat " + Num(*latitude_deg) + ": expected degrees in [-90, 90] (north positive)";
    return false;
  }
  if (!longitude_deg) {
    *why = "--lon DEG is required (degrees, east positive)";
    return false;
  }
  if (!(std::abs(*longitude_deg) <= 180.0)) {
    *why = "--lon " + Num(*longitude_deg) + ": expected degrees in [-180, 180] (east positive)";
    return false;
  }
  // Physical bounds for a camera under a sky (stricter than NREL SPA's own validity
  // ranges, which the library keeps as a backstop): the deepest ocean floor to the Karman
  // line; sea-level pressures up to the record high with margin; surface air temperatures.
  if (!(elevation_m >= -11000.0 && elevation_m <= 100000.0)) {
    *why = "--elevation-m " + Num(elevation_m) + ": expected metres above sea level in [-11000, 100000]";
    return false;
  }
  if (!(pressure_mbar >= 0.0 && pressure_mbar <= 1200.0)) {
    *why = "--pressure " + Num(pressure_mbar) + ": expected millibars in [0, 1200] (sea level ~1013)";
    return false;
  }
  if (!(temperature_c >= -100.0 && temperature_c <= 100.0)) {
    *why = "--temperature " + Num(temperature_c) + ": expected air temperature in degrees Celsius, [-100, 100]";
    return false;
  }
  if (!(std::abs(delta_t_s) <= 8000.0)) {
    *why = "--delta-t " + Num(delta_t_s) + ": expected seconds with |delta T| <= 8000";
    return false;
  }
  if (!(std::abs(north_longitude_deg) <= 360.0)) {
    *why = "--north-longitude " + Num(north_longitude_deg) + ": expected degrees in [-360, 360]";
    return false;
  }
  std::string spa_why;
  if (!ToSpaInput().IsValid(&spa_why)) {  // backstop: every field above is already checked
    *why = spa_why;
    return false;
  }
  return true;
}

capture::SpaInput SunOptions::ToSpaInput() const {
  capture::SpaInput in = capture::ParseIso8601(time, "--time");
  in.latitude_deg = latitude_deg.value_or(std::numeric_limits<double>::quiet_NaN());
  in.longitude_deg = longitude_deg.value_or(std::numeric_limits<double>::quiet_NaN());
  in.elevation_m = elevation_m;
  in.pressure_mbar = pressure_mbar;
  in.temperature_c = temperature_c;
  in.delta_t_s = delta_t_s;
  return in;
}

nlohmann::json RunSunImpl(const SunOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const capture::SpaInput in = o.ToSpaInput();
  const capture::SpaResult r = capture::ComputeSolarPosition(in);
  const std::array<double, 3> dir = capture::SunDirectionInFrame(r, o.north_longitude_deg);
  const double latlong_lon = capture::LatLongLongitudeOfAzimuthDeg(r.azimuth_deg, o.north_longitude_deg);
  Log("sun", o.time + " at lat " + Num(*o.latitude_deg) + ", lon " + Num(*o.longitude_deg) + ": zenith " +
                 Num(r.zenith_deg, 8) + " deg, azimuth " + Num(r.azimuth_deg, 8) + " deg (from north, eastward), elevation " +
                 Num(r.elevation_deg, 8) + " deg" + (r.elevation_deg < 0.0 ? " (below the horizon)" : ""));
  Log("sun", "lat-long frame (north at longitude " + Num(o.north_longitude_deg) + "): --sun-elevation " +
                 Num(r.elevation_deg, 8) + " --sun-azimuth " + Num(latlong_lon, 8));
  return {{"time", o.time},
          {"utc_offset_h", in.timezone_h},
          {"latitude_deg", in.latitude_deg},
          {"longitude_deg", in.longitude_deg},
          {"elevation_m", in.elevation_m},
          {"pressure_mbar", in.pressure_mbar},
          {"temperature_c", in.temperature_c},
          {"delta_t_s", in.delta_t_s},
          {"zenith_deg", r.zenith_deg},
          {"azimuth_deg", r.azimuth_deg},
          {"elevation_deg", r.elevation_deg},
          {"azimuth_astro_deg", r.azimuth_astro_deg},
          {"refraction_deg", r.refraction_deg},
          {"julian_day", r.julian_day},
          {"equation_of_time_min", r.equation_of_time_min},
          {"right_ascension_deg", r.right_ascension_deg},
          {"declination_deg", r.declination_deg},
          {"above_horizon", r.elevation_deg > 0.0},
          {"latlong",
           {{"north_longitude_deg", o.north_longitude_deg},
            {"sun_azimuth_deg", latlong_lon},
            {"sun_elevation_deg", r.elevation_deg},
            {"sun_dir", dir}}},
          {"algorithm", "NREL SPA (Reda & Andreas 2004, NREL/TP-560-34302)"}};
}

SunOptions ParseSunArgs(int argc, char** argv) {
  VerbCommandLine cl("sun", "skycal sun: the sun's position for a place and time (NREL SPA, Reda & Andreas 2004)",
                     "  skycal sun --time ISO8601 --lat DEG --lon DEG [--elevation-m M] [--pressure MBAR]\n"
                     "             [--temperature C] [--delta-t S] [--north-longitude DEG] [--json]",
                     "Zenith and elevation are topocentric and include atmospheric refraction; azimuth is from\n"
                     "north, eastward, in [0, 360). Uncertainty +/-0.0003 deg (the algorithm's, for exact inputs).");
  SunOptions o;
  bool json = false;
  cl.Text("--time", &o.time, "ISO8601",
          "local date and time with its UTC offset, or UTC with Z (required):\n"
          "2003-10-17T12:30:30-07:00, 2024-06-21T12:00:00Z, ...+05:30\n"
          "(a time without an offset is refused; dates before 1582-10-15 are\n"
          "Julian-calendar dates, as in the SPA; years -2000..6000)");
  cl.Number("--lat", &o.latitude_deg, "DEG", "observer latitude, degrees in [-90, 90], north positive (required)");
  cl.Number("--lon", &o.longitude_deg, "DEG", "observer longitude, degrees in [-180, 180], east positive (required)");
  cl.Number("--elevation-m", &o.elevation_m, "M", "observer elevation above sea level in metres, [-11000, 100000] (default 0)");
  cl.Number("--pressure", &o.pressure_mbar, "MBAR", "annual mean local pressure, millibars in [0, 1200] (default 1013.25)");
  cl.Number("--temperature", &o.temperature_c, "C", "annual mean local temperature, Celsius in [-100, 100] (default 15)");
  cl.Number("--delta-t", &o.delta_t_s, "S", "TT - UT1 in seconds (default 67; about 69 in the 2020s)");
  cl.Number("--north-longitude", &o.north_longitude_deg, "DEG",
            "lat-long longitude of geographic north in the frame (camera heading;\n"
            "default 0: north is +Z, east is -X). Compass azimuth A maps to\n"
            "lat-long longitude = north - A (the unmirrored sky seen from inside)");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  return o;
}

int RunSun(int argc, char** argv) {
  return RunVerb("sun", WantsJson(argc, argv), [&]() { return RunSunImpl(ParseSunArgs(argc, argv)); });
}

}  // namespace skycal::cli
