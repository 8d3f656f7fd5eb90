// fit.json, the record `skycal fit` writes beside preset.json, as one typed struct with its
// one writer and one reader. The fit's own reports are the typed records of fit_report.h;
// the sections other modules own and document (the resolved fit options, the cloud
// lighting fit's `clouds` and `cloud_stats`, a reference's `cloud_mask`) stay JSON objects
// here, written and read whole. docs/file-formats.md lists the fields.
//
// Keys are written sorted (nlohmann::json's object order), so the text depends only on the
// values. A double that is not finite is written as null and read back as NaN.
#pragma once
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/fit/fit_report.h"
#include "skycal/fit/reference.h"

namespace skycal::fit {

struct FitResult;

// The version this skycal writes and reads (fit.json's `schema_version`).
inline constexpr int kFitResultSchemaVersion = 1;

// references[i].sun: the sun a reference's gray probe saw (fit --probe), skycal/fit/sky_fit.h's
// ProbeSun with the sample file it came from.
struct FitProbeSunEntry {
  bool observable = false, visible = false;
  std::array<double, 3> illuminance_rgb{}, illuminance_rgb_model{}, fitted_illuminance_rgb_model{};
  double fraction = 0.0, residual = 0.0, log_rmse = 0.0;
  int samples = 0, sun_facing_samples = 0, ground_facing_samples = 0;
  std::string probe;                             // the probe samples file
  std::string note;                              // written when not empty
  std::optional<double> illuminance_lux;         // --absolute fits
  std::optional<std::array<double, 3>> sun_tint_rgb;  // when the probe saw the sun
  bool operator==(const FitProbeSunEntry&) const = default;
};

// references[i].cloud_mask (fit --cloud-mask): the sky pixels whose cloud probability reached
// the threshold, left out of the fit.
struct FitCloudMaskEntry {
  long long cloudy_pixels = 0;
  double fraction = 0.0;   // of the sky pixels before masking
  double threshold = 0.5;  // cloud probability
  std::string source;      // "mask.cloud channel" or "estimated: ..."
  bool operator==(const FitCloudMaskEntry&) const = default;
};

// references[i].images: the previews, relative to the fit directory.
struct FitReferenceImages {
  std::string reference, fit, error;
  bool operator==(const FitReferenceImages&) const = default;
};

// One reference of fit.json's `references`.
struct FitReferenceEntry {
  std::string name, path;
  double rel_rmse = 0.0, log_rmse = 0.0, exposure = 1.0;
  std::array<double, 3> sun_direction{};
  std::optional<double> sun_elevation_deg;  // absent from fit.json written by hand
  std::string sun_source;
  std::vector<int> observed_lut_rows;
  double clip_level = 0.0;
  std::optional<MaskCounts> pixels;  // absent from fit.json written by hand
  std::optional<FitProbeSunEntry> sun;
  std::optional<FitReferenceImages> images;        // absent when the previews were skipped
  std::optional<double> sun_illuminance_at_ground_lux;  // the fitted preset's sun (model units)
  std::optional<FitCloudMaskEntry> cloud_mask;
  bool operator==(const FitReferenceEntry&) const = default;
};

// `calibration`: what `skycal calibrate` found in the photo and what the game will show
// (absent from a plain fit). The game's image is the calibrated preset rendered as the game
// renders it at the photo's sun, size and exposure (render.exr), compared with the photo
// over the sky pixels above the horizon (core/appearance.h).
struct FitCalibration {
  std::string photo;                       // the photograph as given
  std::string sky_kind, sky_kind_reason;   // capture::SkyKind and the statistic that decided it
  double sky_share = 0.0, zenith_sky_share = 0.0, zenith_blue = 0.0, texture = 0.0, point_sources = 0.0;
  std::optional<double> cloud_share;       // absent when not measured
  std::string sun_source;                  // "option", "attribute", "disc", "time and place", "sky"
  std::optional<double> sun_uncertainty_deg;  // "sky" (and the azimuth of "time and place")
  std::string mask, render;                // files in the fit directory
  int game_sky_pixels = 0;
  double game_per_pixel_log_rmse = 0.0;    // natural log
  double game_appearance_error = 0.0;      // natural log, RMS over bands x statistics
  // The sun's cone left out of both (degrees; 0: none): `skycal compare --photo photo.exr
  // --game render.exr --mask mask.exr --sun-cone` of it gives the same two numbers.
  double game_sun_cone_deg = 0.0;
  // Intersection over union of the game's clouds (transmittance < 0.5) and the photo's (cloud
  // probability >= 0.5) over the same pixels; absent when no clouds were drawn.
  std::optional<double> game_cloud_iou;
  double seconds = 0.0;                    // the whole calibration of this photo, wall clock
  bool operator==(const FitCalibration&) const = default;
};

// Everything fit.json holds. Optional sections: probe (with probe samples), linear_start
// (unless --no-linear-start), cloud_stats (--clouds stats), time_of_day_h.
struct FitResultFile {
  int schema_version = kFitResultSchemaVersion;
  double haziness_g = 0.0;
  double time_s = std::numeric_limits<double>::quiet_NaN();  // NaN: not recorded
  int iterations = 0;
  std::string termination, backend_device;
  std::optional<ProbeReport> probe;
  LinearStartReportOut linear_start;
  std::vector<LevelReport> levels;
  std::vector<SkipNote> skipped;
  std::vector<FitDecision> decisions;
  std::vector<UnobservedRow> unobserved_lut_rows;
  std::vector<FitReferenceEntry> references;
  std::vector<std::string> warnings;
  nlohmann::json options = nlohmann::json::object();  // the resolved fit options (cli: ResolvedFitOptionsJson)
  nlohmann::json clouds;       // the cloud lighting fit's record (skycal/controllers/fit_clouds.h); null when absent
  nlohmann::json cloud_stats;  // --clouds stats (skycal/controllers/fit_cloud_stats.h); null when absent
  std::optional<double> time_of_day_h;
  std::optional<FitCalibration> calibration;
  std::string out;  // the --out directory as given
  bool operator==(const FitResultFile&) const = default;
};

// The fit's own part of the file from its result: haziness_g, time_s, iterations,
// termination, backend_device, probe, linear_start, levels, skipped, decisions,
// unobserved_lut_rows. The caller adds the references and the rest.
FitResultFile FitResultFileFrom(const FitResult& result);

// The file's JSON (what WriteFitResultFile writes), and one reference's entry alone
// (preset.json's provenance records the references' entries).
nlohmann::json FitResultFileJson(const FitResultFile& file);
nlohmann::json FitReferenceEntryJson(const FitReferenceEntry& entry);
void WriteFitResultFile(const std::string& path, const FitResultFile& file);

// Reads fit.json. Throws skycal::Error naming the file (and the field) when it is not JSON,
// not an object, lacks a required field (references with name, rel_rmse and log_rmse;
// haziness_g), has a field of the wrong type, or a schema_version other than
// kFitResultSchemaVersion. A file without schema_version reads as version 1.
FitResultFile ReadFitResultFile(const std::string& path);
// The same for a document already parsed; `origin` names it in errors.
FitResultFile FitResultFileFromJson(const nlohmann::json& doc, const std::string& origin);
// The schema_version check alone (for readers that take only a few fields).
void RequireFitResultSchemaVersion(const nlohmann::json& doc, const std::string& origin);

}  // namespace skycal::fit
