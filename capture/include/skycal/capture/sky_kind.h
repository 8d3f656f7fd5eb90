// What kind of sky a photograph shows, so a calibration fits only what the scene has:
// clear, partly cloudy, overcast, twilight, night, or not a sky at all (a canopy, an
// interior, a street with a sliver of sky). Every rule reads a statistic of the photo
// itself over the sky pixels of its automatic segmentation (sky_segmentation.h), and the
// decision says which statistic decided it and against which threshold.
//
// The statistics, and the physics that separates the kinds:
//  - sky share: the sky pixels above the horizon over all pixels above it. Under a canopy
//    or indoors little of the upper hemisphere is sky. The same above 45 degrees: buildings
//    and trees around an open place stand low, a roof or a canopy covers the zenith.
//  - zenith blueness, the median ln(B/R) of the sky above 45 degrees: Rayleigh scattering
//    makes a clear day sky blue (ln B/R well above 0); cloud decks are grey (near 0); the
//    light-polluted night sky is orange-grey, lit by sodium lamps from below; a ceiling lit
//    by tungsten or warm LED lamps is redder still. A daylight zenith is never red: even
//    at sunset it stays blue (Rayleigh scattering, and ozone's Chappuis band).
//  - cloud share, the mean cloud probability (cloud_mask.h) over the sky pixels.
//  - texture, the median local RMS of ln Y about its blur over the sky: cloud edges and
//    stars carry it, a clear sky and a uniform deck do not. Its upper quartile too: in a
//    noise-free image (a game's own render, a denoised photo) the clear sky has no texture
//    at all, and clouds over less than half the sky leave the median at the clear sky's.
//  - point sources, strict local maxima of Y above all eight neighbours: stars.
//  - the sun's elevation, when it is known (disc, time and place, or the sky's pattern):
//    below the horizon the sky is twilight (civil to astronomical, down to -18 degrees,
//    the sun's depression at which astronomical twilight ends) or night.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::capture {

enum class SkyKind { kClear, kPartlyCloudy, kOvercast, kTwilight, kNight, kNotSky };
const char* ToString(SkyKind kind);  // "clear", "partly cloudy", "overcast", "twilight", "night", "not a sky"

struct SkyFeatures {
  double sky_share = 0.0;          // sky pixels / pixels above the horizon, by solid angle
  double zenith_sky_share = 0.0;   // the same above 45 degrees elevation
  double zenith_blue = 0.0;        // median ln(B/R) over sky pixels above 45 degrees elevation (natural log)
  double cloud_share = 0.0;        // mean cloud probability over sky pixels; NaN when not measured
  double texture = 0.0;            // median local RMS of ln Y about its Gaussian blur over sky pixels (natural log)
  double texture_q75 = 0.0;        // its 75th percentile
  double sky_luminance = 0.0;      // median Rec.709 luminance of the sky pixels (the file's units)
  double point_sources = 0.0;      // share of sky pixels above 20 degrees brighter than all 8 neighbours by kPointContrast (stars)
  std::optional<double> sun_elevation_deg;  // when the sun is known
  // The sun above came from a disc detector, which a street lamp or the moon can fool; a sun
  // given, recorded or computed from the time and place overrides the stars rule.
  bool sun_from_disc = false;
};

struct SkyKindOptions {
  double min_sky_share = 0.25;       // below: not a sky, (0, 1)
  // Below: not a sky, the zenith covered (a roof, a canopy), (0, 1]. Open skies, bundled
  // and held out, are at least 0.87 (a city's towers); a carport roof 0.03
  // (bench/results/calibrate.md).
  double min_zenith_sky_share = 0.5;
  double lamp_blue = -0.2;           // zenith ln(B/R) below: not a sky (a lamp-lit ceiling), [-3, 0]
  double night_sun_deg = -18.0;      // sun at or below: night (astronomical twilight's end), [-30, 0]
  double twilight_sun_deg = 0.0;     // sun below (and above night_sun_deg): twilight, [-10, 5]
  // Stars: a share of point sources at or above night_points with a zenith no bluer than
  // night_blue is a night sky, unless a sun not from the disc detector is up (a lamp passes
  // for a disc; the detail of broken cloud under a known sun passes for stars).
  double night_points = 4e-4;        // (0, 1)
  double night_blue = 0.4;           // [-2, 2]
  double overcast_cloud_share = 0.7; // cloud share at or above, without cloud texture: overcast, (0, 1]
  double overcast_blue = 0.35;       // ... or a zenith ln(B/R) below this (a grey deck) without cloud texture, [-1, 2]
  // Cloud edges: a texture at or above this is a sky with clouds in it (partly cloudy);
  // below it and grey, one uniform deck.
  double cloudy_texture = 0.01;      // natural-log RMS, (0, 10)
  // ... or an upper quartile at or above this: cloud edges over at least a quarter of the sky,
  // between clear photos' upper quartiles and those of rendered partly cloudy skies whose
  // median is a clear sky's (bench/results/sky_segmentation.md, "Cloud edges without noise").
  double cloudy_texture_q75 = 0.05;  // natural-log RMS, (0, 10)
  // False and the field, its value and the expectation in *why.
  bool IsValid(std::string* why) const;
};

// `frame`: a lat-long (core/latlong.h); `sky`: per pixel, 1 sky, 0 not (SkyMask::sky);
// `cloud_probability`: per pixel in [0, 1] or empty (not measured). Throws skycal::Error on
// sizes that do not match the frame.
SkyFeatures MeasureSkyFeatures(const ImageRGB& frame, const std::vector<float>& sky,
                               const std::vector<float>& cloud_probability, std::optional<double> sun_elevation_deg);

struct SkyKindDecision {
  SkyKind kind = SkyKind::kClear;
  std::string reason;  // the statistic that decided, its value and the threshold
};
// Cloud edges in the sky: texture >= cloudy_texture or its upper quartile >= cloudy_texture_q75
// (what makes a blue sky partly cloudy, and a twilight sky one with clouds to place).
bool HasCloudEdges(const SkyFeatures& features, const SkyKindOptions& options);
// Throws skycal::Error on invalid options.
SkyKindDecision ClassifySky(const SkyFeatures& features, const SkyKindOptions& options);

}  // namespace skycal::capture
