// `skycal sun`: where the sun is for a place and time (NREL's Solar Position Algorithm,
// capture/solar_position.h), as zenith/azimuth and as a direction in the project's lat-long
// frame, ready for `render --sun-elevation/--sun-azimuth` or `--sun-dir`.
#pragma once
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/solar_position.h"

namespace skycal::cli {

struct SunOptions {
  std::string time;                      // ISO 8601 with a UTC offset or Z, required
  std::optional<double> latitude_deg;    // [-90, 90], north positive, required
  std::optional<double> longitude_deg;   // [-180, 180], east positive, required
  double elevation_m = 0.0;              // observer height above sea level
  double pressure_mbar = 1013.25;        // [0, 5000] (refraction)
  double temperature_c = 15.0;           // (-273, 6000] (refraction)
  double delta_t_s = 67.0;               // TT - UT1, |.| <= 8000 s
  double north_longitude_deg = 0.0;      // lat-long longitude of geographic north (camera heading)

  bool IsValid(std::string* why) const;  // names the option at fault
  capture::SpaInput ToSpaInput() const;  // valid options only
};

// Computes the position; returns the JSON summary. Throws skycal::Error on invalid options.
nlohmann::json RunSunImpl(const SunOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
SunOptions ParseSunArgs(int argc, char** argv);
int RunSun(int argc, char** argv);

}  // namespace skycal::cli
