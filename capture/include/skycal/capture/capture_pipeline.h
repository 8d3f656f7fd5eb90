// The capture pipeline: exposure brackets from a camera (or a rig of cameras) to a reference
// frame: HDR merge, colour conversion to the working space, lens unwrap / rig stitch to the
// lat-long convention, the sun (NREL SPA from time and place, and/or detected), mask
// channels and metadata. Its own target (skycal_capture_pipeline) because the cloud mask
// renders the clear sky (skycal_render) and the colour stage uses OCIO (skycal_color), which
// the capture primitives below it do not need.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/capture/color_chart.h"
#include "skycal/capture/hdr_merge.h"
#include "skycal/capture/lens.h"
#include "skycal/capture/star_removal.h"

namespace skycal::capture {

struct CaptureOptions {
  std::vector<std::string> brackets;        // one camera's exposures (8/16-bit images)
  std::vector<double> exposure_times_s;     // empty: EXIF
  MergeOptions merge;
  std::string rig_path;                     // alternative: a rig file whose cameras name HDR EXRs
  LensParams lens;                 // single camera
  // Which lens flags the user gave: a lat-long input has no optical axis, field of view,
  // image circle or radial distortion, so giving any of these with --lens latlong (or any
  // lens flag with --rig) is refused as contradictory rather than silently ignored.
  bool lens_model_given = false, lens_center_given = false, lens_radius_given = false;
  bool lens_fov_given = false, kb_given = false, vignetting_given = false;
  // The lensfun profile (lens_profile.h) of the single camera's lens: "" looks it up from the
  // first bracket's EXIF (no match: a message, and on without); "none" turns it off; else
  // "LENS_MAKER:LENS_MODEL[@CAMERA_MAKER:CAMERA_MODEL]" (no match: an error). Its vignetting
  // and TCA correct the merged (linear) image, its distortion, projection and focal length
  // the unwrap; the hand-given lens fields above override it field by field.
  std::string lens_profile;
  // yaw, pitch, roll in degrees; unset: the identity for --lens latlong (the panorama is
  // already in the world's lat-long), 0,90,0 (looking straight up) for the fisheyes.
  std::optional<std::array<double, 3>> camera_ypr_deg;
  std::array<double, 3> CameraRotationDeg() const;  // the one used (defaults above)
  std::string input_colorspace = "lin_rec709";
  // Colour-chart correction (capture/color_chart.h), camera RGB -> scene-linear Rec.709,
  // replacing --input-colorspace: a `skycal chart` JSON, or a chart image fitted now (an
  // 8/16-bit image is linearised through this capture's response curve; an EXR is linear).
  std::string color_correction_path;
  std::string chart_path;
  std::optional<std::array<double, 8>> chart_corners;  // with chart_path: not detected
  std::string chart_label;
  // Night frames: stars removed from the lat-long (capture/star_removal.h), mask.stars plane.
  bool remove_stars = false;
  StarRemovalOptions stars;
  std::string time_iso;                     // with lat/lon: the sun by NREL SPA
  std::optional<double> latitude_deg, longitude_deg;
  double north_longitude_deg = 0.0;         // lat-long longitude of geographic north
  int width = 2048, height = 1024;          // output lat-long, pixels
  std::string out;
  bool verbose = true;                      // progress lines on stderr ([capture] ...); skycal bench turns them off
  // The clear-sky preset the cloud mask compares against; empty: the bundled
  // datasets/presets/default_clear.json of this checkout.
  std::string clear_sky_preset;
  bool IsValid(std::string* why) const;
};

// The controller: runs the stages (merge, colour, unwrap, sun, masks, write), writes
// options.out and returns the summary (stage timings in milliseconds under "stages", the
// stages skipped and why under "skipped"). Throws skycal::Error.
nlohmann::json RunCapturePipeline(const CaptureOptions& options);

// A colour-chart correction's summary: label, source, matrix, CIEDE2000 before and after
// (mean, max) and how the chart was found.
nlohmann::json ChartSummary(const ColorCorrection& c);

}  // namespace skycal::capture
