#include "render_clouds.h"

#include <cmath>

#include "option_values.h"
#include "skycal/core/error.h"

namespace skycal::cli {

clouds::MarchOptions CloudMarchOptions(const CloudOptions& o) {
  clouds::MarchOptions m = o.naive ? clouds::MarchOptions::Naive() : clouds::MarchOptions{};
  std::string why;
  if (o.steps) {
    const std::vector<double> v = ParseNumberList(*o.steps, "--cloud-steps");
    if (v.size() != 2) throw Error("--cloud-steps: expected ZENITH,HORIZON (two sample counts), got '" + *o.steps + "'");
    for (double s : v) {
      if (s != std::floor(s) || std::abs(s) > 1e9) throw Error("--cloud-steps: expected integers, got '" + *o.steps + "'");
    }
    m.steps_zenith = static_cast<int>(v[0]);
    m.steps_horizon = static_cast<int>(v[1]);
    if (!m.IsValid(&why)) throw Error("--cloud-steps: " + why);
  }
  if (o.light_samples) {
    m.light_samples = ParseInteger(*o.light_samples, "--cloud-light-samples");
    if (!m.IsValid(&why)) throw Error("--cloud-light-samples: " + why);
  }
  if (o.cheap_light_opacity) {
    m.cheap_light_opacity = ParseNumber(*o.cheap_light_opacity, "--cloud-cheap-light-opacity");
    if (!m.IsValid(&why)) throw Error("--cloud-cheap-light-opacity: " + why);
  }
  return m;
}

controllers::GameCloudOptions ToGameClouds(const CloudOptions& o, const clouds::MarchOptions& march) {
  controllers::GameCloudOptions c;
  c.enabled = o.enabled;
  c.weather_map = o.weather_map;
  c.time_s = o.time_s;
  c.march = march;
  return c;
}

}  // namespace skycal::cli
