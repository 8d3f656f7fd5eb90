// Private: automatic exposure and input sanitising for display previews.
#pragma once
#include <cstddef>

#include "skycal/core/image.h"

namespace skycal::color::detail {

// Mid grey in scene-linear units: the value the log-average luminance is mapped to.
constexpr double kMidGrey = 0.18;

// Largest scene-linear value handed to the view transform after exposure. +Inf (and any
// overflow from the 2^ev multiply) becomes this: far above where every view saturates
// (the ACES SDR curve reaches display white near 16), yet safe for OCIO's float math.
constexpr float kMaxSceneValue = 1.0e6f;

struct AutoExposure {
  double ev = 0.0;               // stops; 0 when no pixel qualified
  double log_average = 0.0;      // geometric-mean luminance of the qualifying pixels
  size_t pixels_used = 0;        // pixels with all channels finite and luminance > 0
};

// Exposure (in stops) that maps the log-average Rec.709 luminance of the finite, positive
// pixels to kMidGrey: ev = log2(0.18) - mean(log2 Y). Rec.709 weights because skycal
// images are scene-linear Rec.709 (core/image.h); for other input spaces it is an
// approximation, which is fine for picking a preview exposure.
AutoExposure ComputeAutoExposure(const ImageRGB& linear);

// Multiplies every value by `scale` and makes it displayable: NaN and negatives -> 0,
// +Inf and overflow -> kMaxSceneValue. Returns how many input values were NaN, infinite
// or negative.
size_t ExposeAndSanitize(ImageRGB& image, float scale);

}  // namespace skycal::color::detail
