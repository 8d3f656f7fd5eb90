// Plain OCIO colour-space conversion of an RGB image, in place.
#include "ocio_config.h"
#include "skycal/color/preview.h"
#include "skycal/core/error.h"

namespace skycal::color {

void ConvertColorspace(ImageRGB& image, const std::string& from, const std::string& to,
                       const std::string& config_path) {
  const detail::LoadedConfig cfg = detail::LoadConfig(config_path);
  detail::RequireColorSpace(cfg, from, "source");
  detail::RequireColorSpace(cfg, to, "destination");
  const std::string what =
      "OCIO config '" + cfg.path + "': conversion '" + from + "' -> '" + to + "'";
  detail::RequireWellFormed(image, what);
  try {
    detail::ApplyInPlace(cfg.config->getProcessor(from.c_str(), to.c_str()), image);
  } catch (const OCIO_NAMESPACE::Exception& e) {
    throw Error(what + ": " + e.what());
  }
}

}  // namespace skycal::color
