// Internal helpers of the sun-from-probe step (public API: skycal/fit/sky_fit.h).
#pragma once
#include <array>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/core/luminance.h"
#include "skycal/fit/sky_fit.h"

namespace skycal::fit {

inline double Rec709Luminance(const std::array<double, 3>& rgb) {
  return skycal::Rec709Luminance(rgb);
}

// Parses a "skycal-probe-samples" document; `origin` names it in errors.
ProbeSamples ProbeSamplesFromJson(const nlohmann::json& doc, const std::string& origin);

}  // namespace skycal::fit
