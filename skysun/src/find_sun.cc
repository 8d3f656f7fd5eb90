#include "skycal/skysun/find_sun.h"

#include "skycal/capture/sky_segmentation.h"
#include "skycal/capture/sun_detect.h"

namespace skycal::skysun {

std::optional<FoundSun> FindSun(const ImageRGB& latlong, double min_disc_contrast, const SkySunOptions& options,
                                std::string* why) {
  FoundSun f;
  if (const auto d = capture::DetectSun(latlong, &f.disc_refusal, min_disc_contrast)) {
    f.direction = d->direction;
    f.source = "disc";
    f.disc_contrast = d->contrast;
    f.disc_peak_luminance = d->peak_luminance;
    f.disc_region_pixels = d->region_pixels;
    f.disc_clipped = d->clipped;
    return f;
  }
  // No disc: the sky pixels the segmentation keeps (no sun known yet, so no glare exclusion
  // around it), then the sky's pattern.
  const capture::SkyMask mask = capture::EstimateSkyMask(latlong, std::nullopt, capture::SkyMaskOptions{});
  std::string sky_why;
  const std::optional<SkySunEstimate> e = EstimateSunFromSky(latlong, mask.sky, options, &sky_why);
  if (!e) {
    *why = "no sun disc (" + f.disc_refusal + "); " + sky_why;
    return std::nullopt;
  }
  f.direction = e->direction;
  f.source = "sky";
  f.uncertainty_deg = e->uncertainty_deg;
  f.sky = e;
  return f;
}

}  // namespace skycal::skysun
