// The sun direction options shared by verbs: --sun-elevation DEG --sun-azimuth DEG (lat-long
// latitude and longitude) or --sun-dir X,Y,Z, exactly one form.
#pragma once
#include <array>
#include <optional>
#include <string>

namespace skycal::cli {

// False, with the reason naming the option, unless exactly one complete, finite form is given.
bool ValidSunChoice(const std::optional<double>& elevation_deg, const std::optional<double>& azimuth_deg,
                    const std::optional<std::array<double, 3>>& dir, std::string* why);
// The unit vector toward the sun (for a valid choice).
std::array<double, 3> SunDirectionFromChoice(const std::optional<double>& elevation_deg,
                                             const std::optional<double>& azimuth_deg,
                                             const std::optional<std::array<double, 3>>& dir);

}  // namespace skycal::cli
