// `skycal capture`: exposure brackets from a camera (or a rig of cameras) to a reference
// frame: HDR merge, colour conversion to the working space, lens unwrap / rig stitch to the
// lat-long convention, the sun (NREL SPA from time and place, and/or detected), mask
// channels and metadata.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/capture/hdr_merge.h"
#include "skycal/capture/lens.h"

namespace skycal::cli {

struct CaptureOptions {
  std::vector<std::string> brackets;        // one camera's exposures (8/16-bit images)
  std::vector<double> exposure_times_s;     // empty: EXIF
  capture::MergeOptions merge;
  std::string rig_path;                     // alternative: a rig file whose cameras name HDR EXRs
  capture::LensParams lens;                 // single camera
  bool lens_center_given = false, lens_radius_given = false;
  std::array<double, 3> camera_ypr_deg{0.0, 90.0, 0.0};  // yaw, pitch, roll; default: looking up
  std::string input_colorspace = "lin_rec709";
  std::string time_iso;                     // with lat/lon: the sun by NREL SPA
  std::optional<double> latitude_deg, longitude_deg;
  double north_longitude_deg = 0.0;         // lat-long longitude of geographic north
  int width = 2048, height = 1024;          // output lat-long, pixels
  std::string out;
  bool IsValid(std::string* why) const;
};

nlohmann::json RunCaptureImpl(const CaptureOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
CaptureOptions ParseCaptureArgs(int argc, char** argv);
int RunCapture(int argc, char** argv);

}  // namespace skycal::cli
