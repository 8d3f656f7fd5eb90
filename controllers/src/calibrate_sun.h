// The sun of a photograph for calibrate, wherever it is, in this order: given outright;
// the file's sunDirection attribute; the disc; the time and place (NREL SPA) with the
// azimuth from north when given, else from the sky's pattern; the sky's pattern alone
// (skysun: the circumsolar glow and the gradients, below the horizon at twilight too).
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/controllers/calibrate.h"
#include "skycal/core/image.h"

namespace skycal::controllers {

// A sun disc in an HDR photo is thousands of times the median sky; a twilight glow behind
// a ridge or the moon reach tens to a hundred (capture::DetectSun's contrast).
inline constexpr double kCalibrateDiscContrast = 300.0;

struct PhotoSun {
  std::optional<std::array<double, 3>> direction;  // unit, toward the sun (core/latlong.h)
  std::string source;    // "option", "attribute", "disc", "time and place", "time and place, azimuth from the sky", "sky"
  std::optional<double> uncertainty_deg;  // the sky's estimate (its azimuth's, with the time and place)
  std::string refusal;   // no direction: why each way failed
};

// The sun that needs no sky mask: given, the frame's sunDirection attribute (`file_sun`), or
// the disc; else no direction and the disc's refusal.
PhotoSun PlainPhotoSun(const ImageRGB& frame, const std::optional<std::array<double, 3>>& file_sun,
                       const CalibrateOptions& o);
// The hidden sun: the time and place, else the sky's pattern over `sky` (the automatic sky
// mask, 1 sky); `no_disc` is PlainPhotoSun's refusal, carried into this one's.
PhotoSun HiddenPhotoSun(const ImageRGB& frame, const std::vector<float>& sky, const CalibrateOptions& o,
                        const std::string& no_disc);
// Both in order. Throws skycal::Error naming the option field on a time that does not parse.
PhotoSun ChoosePhotoSun(const ImageRGB& frame, const std::vector<float>& sky,
                        const std::optional<std::array<double, 3>>& file_sun, const CalibrateOptions& o);

// An overcast sky whose sun nothing places: the CIE overcast term that carries it does not
// depend on the sun, so a nominal one is taken where the deck is brightest
// (capture::BrightestSkyPatch): the peak of the sky pixels' luminance above 5 degrees,
// smoothed by a Gaussian of 5 degrees (the size of a thin deck's bright patch round the sun it
// hides), to the pixel. Its uncertainty is
// unbounded (90 deg). To the pixel because the atmosphere's glow round the nominal sun is steep
// in azimuth: 10-degree cells put it up to 5 degrees off the patch. Nothing when no sky pixel
// above 5 degrees has half of its neighbourhood sky.
std::optional<PhotoSun> NominalOvercastSun(const ImageRGB& frame, const std::vector<float>& sky);

}  // namespace skycal::controllers
