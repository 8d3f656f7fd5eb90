#include "skycal/clouds/composite.h"

#include "skycal/core/error.h"

namespace skycal::clouds {

ImageRGB CompositeClouds(const ImageRGB& sky, const CloudImage& clouds) {
  const ImageRGB& c = clouds.radiance;
  if (sky.width != c.width || sky.height != c.height ||
      clouds.transmittance.size() != static_cast<size_t>(c.width) * c.height) {
    throw Error("composite: sky is " + std::to_string(sky.width) + "x" + std::to_string(sky.height) + ", clouds " +
                std::to_string(c.width) + "x" + std::to_string(c.height) + " (expected the same size)");
  }
  ImageRGB out(sky.width, sky.height);
  for (size_t i = 0; i < clouds.transmittance.size(); ++i) {
    const float t = clouds.transmittance[i];
    for (int k = 0; k < 3; ++k) out.pixels[3 * i + k] = sky.pixels[3 * i + k] * t + c.pixels[3 * i + k];
  }
  return out;
}

}  // namespace skycal::clouds
