// Private helpers around OCIO: loading a config and resolving names, turning every OCIO
// failure into a skycal::Error that names the config and the item at fault.
#pragma once
#include <OpenColorIO/OpenColorIO.h>

#include <string>

#include "skycal/core/image.h"

namespace skycal::color::detail {

namespace OCIO = OCIO_NAMESPACE;

// A loaded config and the path it came from (for error messages).
struct LoadedConfig {
  OCIO::ConstConfigRcPtr config;
  std::string path;
};

// Loads `path` (empty: DefaultConfigPath()). Throws skycal::Error if the file is missing,
// unreadable, or fails to parse or validate.
LoadedConfig LoadConfig(const std::string& path);

// Throws skycal::Error naming the config and listing the known colour spaces unless
// `name` is a colour space, role or alias in the config.
void RequireColorSpace(const LoadedConfig& cfg, const std::string& name, const char* what);

// Returns `view`, or the display's default view when `view` is empty. Throws
// skycal::Error listing the known displays / views if either is unknown.
std::string ResolveView(const LoadedConfig& cfg, const std::string& display,
                        const std::string& view);

// Applies `processor` to the interleaved RGB floats of `image` in place.
void ApplyInPlace(const OCIO::ConstProcessorRcPtr& processor, ImageRGB& image);

// Throws skycal::Error unless `image` is non-empty and its pixel buffer matches its size.
void RequireWellFormed(const ImageRGB& image, const std::string& context);

}  // namespace skycal::color::detail
