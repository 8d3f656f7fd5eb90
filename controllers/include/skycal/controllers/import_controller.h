// `skycal import` as a library: a published equirectangular HDR sky (any RGB(A) EXR, half
// or float, any compression) converted to a reference frame in the project's lat-long
// convention (core/latlong.h, capture/latlong_import.h), with its provenance and, when
// known, its sun. Two entry points: ImportPhoto keeps the frame in memory (what a pipeline
// such as calibrate feeds on), ImportToFile writes it atomically (the verb).
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/time_place.h"
#include "skycal/capture/latlong_import.h"

namespace skycal::controllers {

struct ImportOptions {
  std::string in_path;   // source picture: OpenEXR (RGB(A), half or float, any compression) or Radiance RGBE (.hdr); required
  std::string out_path;  // ImportToFile's output, ending in .exr; ImportPhoto ignores it (may be empty)
  std::optional<std::array<double, 3>> sun_dir;  // the sun given, in the project frame; normalised
  bool detect_sun = false;         // skysun::FindSun on the converted frame (disc, else sky pattern)
  double min_sun_contrast = 20.0;  // FindSun's disc threshold: peak / median sky luminance, >= 1
  // How the source maps directions to pixels; nullopt: capture::ChooseConvention on the
  // file's attributes (the envmap attribute).
  std::optional<capture::SourceConvention> convention = capture::SourceConvention::kBlender;
  bool half = false;  // ImportToFile writes half floats (default float)

  // False and "ImportOptions::field = value (expected ...)" in *why. An empty out_path is
  // valid here (ImportPhoto writes nothing); ImportToFile refuses it.
  bool IsValid(std::string* why) const;
};

// Where the frame's sun came from.
enum class SunSource { kNone, kOption, kAttribute, kDisc, kSkyEstimate };
// "none", "option", "attribute", "disc", "sky-estimate".
const char* ToString(SunSource source);
// The name written in the frame's skycalSunSource attribute and import's summary: ToString,
// except the disc's "detected" (the name fit::Reference reads back).
const char* RecordedName(SunSource source);

struct ImportedSun {
  std::optional<std::array<double, 3>> direction;  // unit vector toward the sun, project frame
  SunSource source = SunSource::kNone;
  // kSkyEstimate: the largest angle to a direction that fits as well (degrees); else 0.
  double uncertainty_deg = 0.0;
  // detect_sun and no sun: FindSun's reasons (no disc; the sky does not place it). Empty otherwise.
  std::string refusal;
  // kDisc: the disc's peak / median sky luminance, its peak (the image's units), its pixels,
  // and whether it is clipped (a plateau: its radiance is unknown).
  double disc_contrast = 0.0, disc_peak_luminance = 0.0;
  int disc_region_pixels = 0;
  bool disc_clipped = false;
  // kSkyEstimate: why the disc was not taken, the sky fit's log RMSE and CIE type (1..15).
  std::string no_disc;
  double sky_log_rmse = 0.0;
  int sky_cie_type = 0;
};

// Pixels with at least one negative / NaN / Inf channel; max and mean over the finite
// values of every channel (the image's units).
struct PixelCensus {
  long long negative = 0, nan = 0, inf = 0;
  double max = 0.0, mean = 0.0;
};

struct ImportedPhoto {
  // In the project's convention, same size as the source; non-finite values set to 0 (the
  // fit masks them like negative ones); sun_direction and the provenance attributes
  // (skycalSource, skycalSourceConvention, skycalSunSource, skycalUnits) set.
  capture::LatLongFrame frame;
  capture::SourceConvention convention = capture::SourceConvention::kBlender;  // the one used
  ImportedSun sun;
  // When and where, from the source's standard EXR attributes (capDate, utcOffset, latitude,
  // longitude, altitude; capture/time_place.h), carried into the frame's attributes.
  capture::TimePlace time_place;
  // What the caller should be told; they name ImportOptions fields, not flags.
  std::vector<std::string> warnings;
  // Provenance: the source's file name, SHA-256, channel names and envmap=latlong attribute.
  std::string source_file, source_sha256;
  std::vector<std::string> source_channels;
  bool source_envmap_latlong = false;
  PixelCensus source_pixels, frame_pixels;  // frame_pixels: before non-finite values are zeroed
  long long zeroed = 0;                     // non-finite values set to 0
};

// Reads options.in_path and converts it. Throws skycal::Error naming the file or the field
// on invalid options, an unreadable or non-2:1 source, or a degenerate one (under 1% of its
// pixels finite with luminance > 0). A detect_sun that finds no sun does not throw: the
// result has no sun and the reasons in sun.refusal.
ImportedPhoto ImportPhoto(const ImportOptions& options);

struct ImportedFile {
  ImportedPhoto photo;
  long long half_clamped = 0;  // half: finite values beyond 65504 the writer clamped
};

// ImportPhoto, then the frame written atomically to options.out_path. Throws skycal::Error
// (and writes nothing) as ImportPhoto does, on an empty, unwritable or input-clobbering
// out_path (checked before reading), and on a detect_sun that finds no sun.
ImportedFile ImportToFile(const ImportOptions& options);

}  // namespace skycal::controllers
