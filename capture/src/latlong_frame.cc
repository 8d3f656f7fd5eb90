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
  attrs.strings.erase(kRowMappingAttribute);
  if (frame.row_mapping) {
    if (frame.row_mapping->rows != frame.radiance.height) {
      throw Error(path + ": row mapping has " + std::to_string(frame.row_mapping->rows) + " rows, the image " +
                  std::to_string(frame.radiance.height));
    }
    attrs.strings[kRowMappingAttribute] = frame.row_mapping->ToAttribute();
  }
  WriteExrRGBWithPlanes(path, frame.radiance, frame.planes, attrs, half ? ExrPixelType::kHalf : ExrPixelType::kFloat);
}

std::optional<std::array<double, 3>> SunDirectionAttribute(const ExrAttributes& attributes, const std::string& path) {
  const auto it = attributes.v3fs.find(kSunAttribute);
  if (it != attributes.v3fs.end()) {
    const auto& v = it->second;
    return latlong::Normalized({v[0], v[1], v[2]}, (path + ": attribute 'sunDirection'").c_str());
  }
  // Present with another type: an error naming the type, never "no sun direction".
  std::string type;
  if (attributes.strings.count(kSunAttribute)) type = "string \"" + attributes.strings.at(kSunAttribute) + "\"";
  if (attributes.floats.count(kSunAttribute)) type = "float";
  if (attributes.other_types.count(kSunAttribute)) type = attributes.other_types.at(kSunAttribute);
  if (!type.empty()) {
    throw Error(path + ": attribute 'sunDirection' is a " + type +
                ": expected a v3f (x, y, z) toward the sun in the lat-long's frame (y up)");
  }
  return std::nullopt;
}

LatLongFrame ReadLatLongFrame(const std::string& path, RowMappingPolicy policy) {
  ExrRGB exr = ReadExrRGB(path);
  LatLongFrame frame;
  frame.radiance = std::move(exr.image);
  if (exr.attributes.other_types.count(kRowMappingAttribute) || exr.attributes.floats.count(kRowMappingAttribute) ||
      exr.attributes.v3fs.count(kRowMappingAttribute)) {
    throw Error(path + ": attribute '" + kRowMappingAttribute + "' is not a string: expected the JSON text of a row mapping");
  }
  if (auto it = exr.attributes.strings.find(kRowMappingAttribute); it != exr.attributes.strings.end()) {
    const RowMapping m = RowMapping::FromAttribute(it->second, path);
    if (m.rows != frame.radiance.height) {
      throw Error(path + ": attribute '" + std::string(kRowMappingAttribute) + "': field 'rows' is " +
                  std::to_string(m.rows) + ", but the image has " + std::to_string(frame.radiance.height) + " rows");
    }
    if (frame.radiance.width < 3) throw Error(path + ": image is " + std::to_string(frame.radiance.width) + " wide, expected >= 3");
    if (policy == RowMappingPolicy::kRefuse) {
      throw Error(path + ": has horizon-biased rows (attribute '" + std::string(kRowMappingAttribute) +
                  "', written by skycal resample): this reader needs a uniform 2:1 lat-long; `skycal fit` and "
                  "`skycal resample` read such frames");
    }
    frame.row_mapping = m;
    exr.attributes.strings.erase(it);
  } else if (frame.radiance.width != 2 * frame.radiance.height) {
    throw Error(path + ": image is " + std::to_string(frame.radiance.width) + "x" +
                std::to_string(frame.radiance.height) + ", expected a 2:1 lat-long (width = 2 x height)");
  }
  frame.sun_direction = SunDirectionAttribute(exr.attributes, path);
  exr.attributes.v3fs.erase(kSunAttribute);
  if (!exr.attributes.envmap_latlong) {
    exr.attributes.strings["skycalWarning"] = "no envmap=latlong attribute; assumed the lat-long convention";
  }
  exr.attributes.envmap_latlong = true;
  frame.extra = std::move(exr.attributes);
  return frame;
}

}  // namespace skycal::capture
