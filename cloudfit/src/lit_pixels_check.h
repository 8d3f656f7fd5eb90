// The size check of cloudfit::LitPixels the light's refinements share (weather_inversion.h).
#pragma once
#include <string>

#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/core/error.h"

namespace skycal::cloudfit {

// Throws skycal::Error, "<who>: <which> has ... expected the view's n pixels each", when
// either of `p`'s vectors is not `n` long.
inline void CheckLitPixels(const LitPixels& p, size_t n, const char* who, const char* which) {
  if (p.opacity.size() != n || p.log_luminance.size() != n)
    throw Error(std::string(who) + ": " + which + " has " + std::to_string(p.opacity.size()) + " opacities and " +
                std::to_string(p.log_luminance.size()) + " log luminances; expected the view's " + std::to_string(n) +
                " pixels each");
}

}  // namespace skycal::cloudfit
