// Star removal for night frames (Forza Horizon 3's pipeline removes the stars from its
// captured skies and draws its own star field in their place: pixel stars turn into
// squares under a photo mode's long lens). Median-based: a star is a small, isolated group
// of pixels well above the median of its neighbourhood; its pixels (and a one-pixel halo
// for the lens's spread) are replaced, per channel, by the median of the same row's
// neighbours (the star's pixels left out), so the sky under it keeps its level and nothing
// around it is blurred. Everything else is left bit for bit.
//
//   StarRemovalResult r = RemoveStars(frame, {});   // r.image, r.mask, r.stars
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/core/image.h"

namespace skycal::capture {

struct StarRemovalOptions {
  int window_px = 7;            // median window side (odd), pixels: several star widths
  // A pixel is a candidate when its luminance exceeds the local median by both
  // `min_contrast` (relative: 0.5 = 50% above) and `threshold_sigma` times the image's noise
  // (1.4826 x the median absolute deviation of luminance minus its local median).
  double min_contrast = 0.5;
  double threshold_sigma = 6.0;
  int max_star_pixels = 12;     // a candidate group larger than this is not a star (moon, lights, cloud edge)
  int max_star_extent_px = 4;   // ... nor one wider or taller than this (x: times 1/cos(latitude), at most 4x,
                                // in a lat-long: a star near the pole is stretched along the row)
  // Isolated: no other candidate within this many pixels of the group (texture, city
  // lights and cloud edges come in clusters; stars on a dark sky do not).
  int isolation_px = 2;
  int halo_px = 1;              // also replaced around the group: the lens's spread of the star
  // Only rows above this elevation (degrees) when the image is a 2:1 lat-long; stars below
  // the horizon are reflections or lights.
  double min_elevation_deg = 0.0;
  bool IsValid(std::string* why) const;  // names the field
  bool operator==(const StarRemovalOptions&) const = default;
};

struct StarRemovalResult {
  ImageRGB image;               // the input with the stars replaced
  std::vector<uint8_t> mask;    // per pixel 1: replaced
  int stars = 0;                // groups removed
  long long pixels_replaced = 0;
  int rejected_large = 0;       // candidate groups too large or wide to be stars
  int rejected_clustered = 0;   // candidate groups not isolated
  double noise_sigma = 0.0;     // the luminance noise the threshold used
  nlohmann::json ToJson() const;  // counts and noise (no pixels)
};

// Throws skycal::Error (naming the option) on invalid options or an empty image.
StarRemovalResult RemoveStars(const ImageRGB& image, const StarRemovalOptions& options);

}  // namespace skycal::capture
