// Display previews of linear HDR images through OpenColorIO, and plain colour-space
// conversions. The default OCIO config is the bundled config/skycal.ocio (scene-linear
// Rec.709 reference, sRGB display with an ACES filmic view and an un-tone-mapped view);
// $OCIO overrides it with a studio config.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::color {

struct PreviewOptions {
  std::string config_path;  // empty: DefaultConfigPath() ($OCIO if set, else the repo config)
  std::string input_colorspace = "lin_rec709";  // colour space (or role) of the input pixels
  std::string display = "sRGB";
  std::string view;          // empty: the config's default view for `display`
  // Exposure in stops (EV), applied as a 2^ev multiply on the linear input before the
  // view transform. NaN: automatic, chosen so the log-average luminance of the finite,
  // positive pixels maps to 0.18 (mid grey). Finite values must lie in [-64, 64].
  double exposure_ev = NAN;

  // True when the options are usable without touching the file system; otherwise
  // writes the reason (naming the field) to *why when why is non-null.
  bool IsValid(std::string* why) const;
};

struct PreviewReport {
  double exposure_ev = 0.0;  // the exposure actually applied, in stops
  std::string config_path;   // the OCIO config actually used
  std::string view;          // the view actually used (the default one resolved)
  // Additions to the agreed interface, for the caller's log: whether exposure_ev was
  // chosen automatically, and one human-readable line per notable event (automatic
  // exposure and the luminance it measured, NaN/Inf/negative values replaced).
  bool auto_exposure = false;
  std::vector<std::string> notes;
};

// Converts a linear RGB image (row 0 on top) through the OCIO display/view transform and
// writes an 8-bit RGB PNG atomically (temporary file beside it, then rename). Non-finite
// and negative values are sanitised (NaN and negatives -> 0, +Inf -> very bright).
// Throws skycal::Error naming the file / config / colour space / display / view on any
// failure; no file (and no temporary) is left behind on failure.
PreviewReport WritePreviewPng(const ImageRGB& linear, const std::string& png_path,
                              const PreviewOptions& options);

// The same transform into an 8-bit RGB buffer (width * height * 3 bytes, interleaved,
// row 0 on top), for composing report images. `report` may be null.
std::vector<uint8_t> ToDisplay8(const ImageRGB& linear, const PreviewOptions& options,
                                PreviewReport* report);

// Plain colour-space conversion of RGB pixels via OCIO (e.g. lin_rec709 -> ACEScg), in
// place. Names may be colour spaces or roles. Values pass through unsanitised (a NaN stays
// a NaN). Throws skycal::Error naming the config / colour space on failure.
void ConvertColorspace(ImageRGB& image, const std::string& from, const std::string& to,
                       const std::string& config_path = "");

// $OCIO when set and non-empty, else the bundled config/skycal.ocio in the data directory
// (skycal::DataPath, core/data_dir.h: the checkout, or share/skycal of an install).
std::string DefaultConfigPath();

}  // namespace skycal::color
