#include "skycal/capture/latlong_frame.h"

#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::capture {

namespace {
constexpr const char* kSunAttribute = "sunDirection";
}

void WriteLatLongFrame(const std::string& path, const LatLongFrame& frame, bool half) {
  ExrAttributes attrs = frame.extra;
  attrs.envmap_latlong = true;
  if (frame.sun_direction) {
    const auto& s = *frame.sun_direction;
    attrs.v3fs[kSunAttribute] = {static_cast<float>(s[0]), static_cast<float>(s[1]), static_cast<float>(s[2])};
  }
  WriteExrRGBWithPlanes(path, frame.radiance, frame.planes, attrs, half ? ExrPixelType::kHalf : ExrPixelType::kFloat);
}

LatLongFrame ReadLatLongFrame(const std::string& path) {
  ExrRGB exr = ReadExrRGB(path);
  LatLongFrame frame;
  frame.radiance = std::move(exr.image);
  if (frame.radiance.width != 2 * frame.radiance.height) {
    throw Error(path + ": image is " + std::to_string(frame.radiance.width) + "x" +
                std::to_string(frame.radiance.height) + ", expected a 2:1 lat-long (width = 2 x height)");
  }
  auto it = exr.attributes.v3fs.find(kSunAttribute);
  if (it != exr.attributes.v3fs.end()) {
    const auto& v = it->second;
    frame.sun_direction = latlong::Normalized({v[0], v[1], v[2]}, (path + ": attribute 'sunDirection'").c_str());
    exr.attributes.v3fs.erase(it);
  } else {
    // Present with another type: an error naming the type, never "no sun direction".
    std::string type;
    if (exr.attributes.strings.count(kSunAttribute)) type = "string \"" + exr.attributes.strings.at(kSunAttribute) + "\"";
    if (exr.attributes.floats.count(kSunAttribute)) type = "float";
    if (exr.attributes.other_types.count(kSunAttribute)) type = exr.attributes.other_types.at(kSunAttribute);
    if (!type.empty()) {
      throw Error(path + ": attribute 'sunDirection' is a " + type +
                  ": expected a v3f (x, y, z) toward the sun in the lat-long's frame (y up)");
    }
  }
  if (!exr.attributes.envmap_latlong) {
    exr.attributes.strings["skycalWarning"] = "no envmap=latlong attribute; assumed the lat-long convention";
  }
  exr.attributes.envmap_latlong = true;
  frame.extra = std::move(exr.attributes);
  return frame;
}

}  // namespace skycal::capture
