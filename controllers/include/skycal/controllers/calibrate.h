// `skycal calibrate`: photographs in, calibrated presets out. For each photo the controller
// finds the sky (automatic segmentation), the sun (its disc; else the time and place; else
// the sky's own luminance pattern), decides what kind of sky it is and what to fit, fits,
// renders the calibrated preset as the game renders it and compares that image with the
// photo. Every choice is recorded in fit.json's `decisions` with its reason.
#pragma once
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "skycal/fit/fit_report.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/render/renderer.h"

namespace skycal::controllers {

struct CalibrateOptions {
  // Lat-long photos (OpenEXR or Radiance .hdr, either convention import accepts), >= 1; a
  // folder stands for the pictures in it (ExpandPhotoFolders).
  std::vector<std::string> photos;
  std::string out_dir;              // DIR: DIR/<photo stem>/ per photo
  // The time and place of the photos (a time-lapse frame's), for the sun when the disc is
  // hidden: ISO 8601 local or UTC time ("2026-06-21T06:30:00+02:00"), degrees north, east.
  std::optional<std::string> time_iso8601;
  std::optional<double> latitude_deg, longitude_deg;
  // The lat-long longitude (degrees) of geographic north: with the time and place, the
  // sun's azimuth too; without it the time gives the elevation and the sky the azimuth.
  std::optional<double> north_longitude_deg;
  // The sun given outright (degrees; the lat-long's azimuth convention, core/latlong.h).
  std::optional<double> sun_elevation_deg, sun_azimuth_deg;
  // Partly cloudy photos: invert the weather map from the photo so that the clouds sit where
  // the photo has them (off: the cloud statistics fit's map, clouds where its noise puts them).
  bool invert_weather = true;
  // Partly cloudy photos: the clouds' shapes given (an RGB EXR weather map: coverage,
  // precipitation, type, over the preset's weather extent) and held: nothing is inverted, the
  // lighting is fitted pixel by pixel on this map, and the preset carries it unchanged.
  // Empty: inverted (or the statistics fit's, invert_weather off).
  std::string weather_map;
  // The start of a clear or partly cloudy photo's fit (a time-lapse's previous frame: a warm
  // start); empty: the bundled default. An overcast photo starts from the default with the
  // overcast term whatever this says.
  std::string init_preset;
  // The photo's time of day (hours, local; the exported keyframe's key) when no time_iso8601
  // gives it (a batch's frames carry it as skycalTimeOfDay).
  std::optional<double> time_of_day_h;
  render::Backend backend = render::Backend::kVulkan;  // the fit's objective and every render
  bool export_tables = true;  // DIR/game: the game tables of every calibrated preset in DIR (exporter)
  bool report = true;         // DIR/report.html over every photo (and DIR/<stem>/report.html)
  bool verbose = true;        // progress lines through `log`
  // Where progress lines go, one line each without a prefix; empty: stderr as "[calibrate] LINE".
  std::function<void(const std::string&)> log;
  // False and the field, its value and the expectation in *why.
  bool IsValid(std::string* why) const;
};

// One photograph's calibration: DIR/<stem>/ holds photo.exr (the photo in the project's
// lat-long convention, with its sun), mask.exr (the automatic sky mask), the fit's files
// (preset.json and its tables, fit.json, fit/, report.png, report.html), render.exr (the
// calibrated preset rendered as the game renders it, in the photo's units) and
// compare.png (photo | game | error).
struct PhotoCalibration {
  std::string photo;                      // as given
  std::string dir;                        // DIR/<stem>; empty when refused
  std::string refusal;                    // why nothing was written (night, not a sky, no sun...)
  std::optional<fit::FitCalibration> calibration;  // fit.json's `calibration`
  std::vector<fit::FitDecision> decisions;          // what was fitted or skipped, and why
  double seconds = 0.0;
};

struct CalibrateResult {
  std::vector<PhotoCalibration> photos;   // in the order given
  std::string game_dir, report_path;      // empty when not written
  std::vector<std::string> warnings;
  double seconds = 0.0;
  int calibrated() const;
};

// Calibrates every photo (each into its own DIR/<stem>, committed whole or not at all), then
// exports the game tables of every calibrated preset in DIR (earlier runs' too) and writes
// the report over DIR. A photo that
// cannot be calibrated (night, not a sky, no sun to be found, unreadable) is listed with its
// reason and leaves nothing behind; the others go on. Throws skycal::Error on invalid
// options, or when DIR cannot be written.
CalibrateResult RunCalibrate(const CalibrateOptions& options);

// The photos with each folder among them replaced by the pictures in it: its regular files
// that start with OpenEXR's or Radiance's magic (the bytes decide, not the name), hidden ones
// left out, sorted by name. *skipped (may be null) gets the folders' other files. Throws
// skycal::Error naming a folder with no picture in it, or one that cannot be read.
std::vector<std::string> ExpandPhotoFolders(const std::vector<std::string>& photos, std::vector<std::string>* skipped);

// One photo (what RunCalibrate does per photo). Throws skycal::Error naming the file on a
// refusal, leaving nothing behind.
PhotoCalibration CalibratePhoto(const std::string& photo, const CalibrateOptions& options);

}  // namespace skycal::controllers
