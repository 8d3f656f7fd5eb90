// What calibrate learns of a photo before it writes anything (the frame, its sky mask, its
// sun, the kind of sky), and what it then fits: the plan, every choice a fit.json decision.
#pragma once
#include <string>
#include <vector>

#include "calibrate_sun.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_kind.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/controllers/calibrate.h"
#include "skycal/controllers/fit_controller.h"
#include "skycal/core/staged_directory.h"

namespace skycal::controllers {

struct PhotoAnalysis {
  capture::LatLongFrame frame;  // the project's lat-long convention
  capture::SkyMask mask;        // automatic (capture::EstimateSkyMask)
  PhotoSun sun;
  std::vector<float> cloud_probability;  // empty without a sun
  capture::SkyFeatures features;
  capture::SkyKindDecision kind;
  // The time and place the sun was sought with: CalibrateOptions' or, without them, the
  // file's own (capture/time_place.h: the EXR's capDate, utcOffset, latitude, longitude).
  std::optional<std::string> time_iso8601;
  std::string time_source;  // "options", the file's, or empty
  std::vector<std::string> warnings;
};

// A progress line of calibrate's (CalibrateOptions::verbose, log; else stderr).
void CalibrateLog(const CalibrateOptions& o, const std::string& line);

// Imports the photo (either lat-long convention), segments it, places the sun and decides
// the kind of sky. Writes nothing. Throws skycal::Error naming the file when it does not read.
PhotoAnalysis AnalysePhoto(const std::string& path, const CalibrateOptions& o);

// Throws skycal::Error naming `path` when the photo cannot be calibrated: a night sky, not a
// sky, or a sun that nothing places.
void RefuseWhatCannotBeCalibrated(const std::string& path, const PhotoAnalysis& a);

struct FitPlan {
  FitControllerOptions fit;
  bool draw_clouds = false;  // the game's image draws the preset's clouds
  bool draw_sun_disc = true; // ... and the sun's disc (not where no sun was seen)
  std::vector<fit::FitDecision> decisions;
};

// The refit's staged inputs (calibrate_weather.cc), removed before the commit.
inline constexpr const char* kInvertedShapesDir = "inverted_shapes";
inline constexpr const char* kRefitInputsDir = "refit_inputs";

// The fit of one photo staged in `out` (photo.exr and mask.exr written there): what the
// kind of sky asks for. An overcast sky writes its start preset (the CIE overcast term
// carrying the sky) into `out` too.
// `final_dir`: where `out` will be committed (the fitted preset takes its name); the fit's
// records name the staged files there (FitControllerOptions::record_path).
FitPlan PlanFit(const PhotoAnalysis& a, const StagedDirectory& out, const std::string& final_dir, const CalibrateOptions& o);

}  // namespace skycal::controllers
