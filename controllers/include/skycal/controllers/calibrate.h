// `skycal calibrate`: photographs in, calibrated presets out. For each photo the controller
// finds the sky (automatic segmentation), the sun (its disc; else the time and place; else
// the sky's own luminance pattern), decides what kind of sky it is and what to fit, fits,
// renders the calibrated preset as the game renders it and compares that image with the
// photo. Every choice is recorded in fit.json's `decisions` with its reason.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace skycal::controllers {

struct CalibrateOptions {
  std::vector<std::string> photos;  // lat-long EXRs (either convention import accepts), >= 1
  std::string out_dir;              // DIR: DIR/<photo stem>/ per photo
  // The time and place of the photos (a time-lapse frame's), for the sun when the disc is
  // hidden: ISO 8601 local or UTC time ("2026-06-21T06:30:00+02:00"), degrees north, east.
  std::optional<std::string> time_iso8601;
  std::optional<double> latitude_deg, longitude_deg;
  // The sun given outright (degrees; the lat-long's azimuth convention, core/latlong.h).
  std::optional<double> sun_elevation_deg, sun_azimuth_deg;
  // False and the field, its value and the expectation in *why.
  bool IsValid(std::string* why) const;
};

}  // namespace skycal::controllers
