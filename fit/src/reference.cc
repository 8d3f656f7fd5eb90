#include "skycal/fit/reference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sun_detect.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/core/sha256.h"

namespace skycal::fit {

nlohmann::json MaskCountsToJson(const MaskCounts& c) {
  return {{"sky_fitted", c.sky},     {"below_horizon", c.below_horizon}, {"sun_cone", c.sun_cone},
          {"invalid", c.invalid},    {"clipped", c.clipped},             {"user_masked", c.user_masked}};
}

namespace {

// A clipping plateau: the largest channel value shared (to 1e-4) by more than 4 pixels of
// distinct directions (the pole rows repeat one direction W times and are left out), over
// at most 10% of the image: a sensor or encoder clamp saturates a compact bright region
// (the sun), while an overcast or uniform sky legitimately has large equal regions.
double FindClipLevel(const ImageRGB& img) {
  const int w = img.width, h = img.height;
  float peak = 0.0f;
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = img.at(x, y, c);
        if (std::isfinite(v)) peak = std::max(peak, v);
      }
  if (!(peak > 0.0f)) return 0.0;
  long long at_peak = 0;
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float m = std::max({img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)});
      if (std::isfinite(m) && m >= peak * (1.0f - 1e-4f)) ++at_peak;
    }
  const long long pixels = static_cast<long long>(w) * std::max(h - 2, 1);
  return (at_peak > 4 && at_peak * 10 < pixels) ? peak : 0.0;
}

}  // namespace

// A pixel value the fit can use: finite, positive, a normal float (denormals below
// FLT_MIN ~1.2e-38 carry a few bits of precision at most) and below 1e37, which leaves the
// model's products (exposure x LUT x phase) room before float overflow. Any scale in
// between is fine: the exposure is fitted (FitOptions::absolute aside).
namespace {
bool UsableValue(float v) { return v >= std::numeric_limits<float>::min() && v <= 1e37f; }
}  // namespace

double Reference::Latitude(int y) const {
  return row_mapping ? row_mapping->Elevation(y) : latlong::Latitude(y, radiance.height);
}

double Reference::PixelSolidAngle(int x, int y) const {
  return row_mapping ? row_mapping->PixelSolidAngle(x, y, radiance.width)
                     : latlong::PixelSolidAngle(x, y, radiance.width, radiance.height);
}

std::array<double, 3> Reference::PixelDirection(int x, int y) const {
  return row_mapping ? row_mapping->PixelDirection(x, y, radiance.width)
                     : latlong::PixelDirection(x, y, radiance.width, radiance.height);
}

namespace {

// The sun direction: the option, the frame's attribute, or detected in the image (not
// with horizon-biased rows).
void SetSunDirection(const std::string& path, const FitOptions& o, const capture::LatLongFrame& frame, Reference* ref) {
  Reference& r = *ref;
  if (o.sun_dir) {
    r.sun_dir = latlong::Normalized(*o.sun_dir, "FitOptions::sun_dir");
    r.sun_source = "option";
  } else if (frame.sun_direction) {
    r.sun_dir = *frame.sun_direction;
    r.sun_source = "attribute";
  } else if (r.row_mapping) {
    throw Error(path + ": no sun direction: a frame with horizon-biased rows ('" + std::string(kRowMappingAttribute) +
                "') needs --sun-dir/--sun-elevation or a 'sunDirection' attribute (detection assumes uniform rows)");
  } else {
    std::string why;
    auto d = capture::DetectSun(r.radiance, &why);
    if (!d) {
      throw Error(path + ": no sun direction: no --sun-dir/--sun-elevation option, no 'sunDirection' attribute, and "
                  "detection failed (" + why + ")");
    }
    r.sun_dir = d->direction;
    r.sun_source = "detected";
    r.warnings.push_back(path + ": sun direction detected from the image (elevation " +
                         std::to_string(latlong::ElevationDeg(r.sun_dir)) + " deg, azimuth " +
                         std::to_string(latlong::AzimuthDeg(r.sun_dir)) + " deg" + (d->clipped ? ", clipped" : "") +
                         "); pass --sun-dir to override");
  }
}

// The user's mask (FitOptions::mask_path; empty: none), the reference's size.
std::vector<float> ReadUserMask(const FitOptions& o, int w, int h) {
  std::vector<float> user;
  if (!o.mask_path.empty()) {
    ExrRGB m = ReadExrRGB(o.mask_path);
    if (m.image.width != w || m.image.height != h) {
      throw Error(o.mask_path + ": mask is " + std::to_string(m.image.width) + "x" + std::to_string(m.image.height) +
                  ", expected the reference's " + std::to_string(w) + "x" + std::to_string(h));
    }
    user = std::move(m.image.pixels);
  }
  return user;
}

// Every pixel's class (the first that applies: below the horizon, invalid, in the sun
// cone, clipped, user-masked, else sky) and the counts.
void ClassifyPixels(const FitOptions& o, const std::vector<float>& user, Reference* ref) {
  Reference& r = *ref;
  const int w = r.radiance.width, h = r.radiance.height;
  const double clip_threshold = r.clip_level > 0 ? o.clip_fraction * r.clip_level : INFINITY;
  const double cos_cone = std::cos(o.sun_cone_deg * M_PI / 180.0);
  r.pixel_class.assign(static_cast<size_t>(w) * h, PixelClass::kSky);
  for (int y = 0; y < h; ++y) {
    const double lat = r.Latitude(y);
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float* p = &r.radiance.pixels[3 * i];
      PixelClass c = PixelClass::kSky;
      const auto v = r.PixelDirection(x, y);
      if (lat <= 0.0) {
        c = PixelClass::kBelowHorizon;
      } else if (!UsableValue(p[0]) || !UsableValue(p[1]) || !UsableValue(p[2])) {
        c = PixelClass::kInvalid;
      } else if (v[0] * r.sun_dir[0] + v[1] * r.sun_dir[1] + v[2] * r.sun_dir[2] >= cos_cone) {
        c = PixelClass::kSunCone;
      } else if (std::max({p[0], p[1], p[2]}) >= clip_threshold) {
        c = PixelClass::kClipped;
      } else if (!user.empty() && !(user[3 * i] >= 0.5f)) {
        c = PixelClass::kUserMasked;
      }
      r.pixel_class[i] = c;
    }
  }
  r.counts = CountPixelClasses(r.pixel_class);
}

}  // namespace

MaskCounts CountPixelClasses(const std::vector<PixelClass>& classes) {
  MaskCounts n;
  for (PixelClass c : classes) {
    switch (c) {
      case PixelClass::kSky: ++n.sky; break;
      case PixelClass::kBelowHorizon: ++n.below_horizon; break;
      case PixelClass::kSunCone: ++n.sun_cone; break;
      case PixelClass::kInvalid: ++n.invalid; break;
      case PixelClass::kClipped: ++n.clipped; break;
      case PixelClass::kUserMasked: ++n.user_masked; break;
    }
  }
  return n;
}

Reference LoadReference(const std::string& path, const FitOptions& o) {
  Reference r;
  r.path = path;
  r.name = std::filesystem::path(path).stem().string();
  capture::LatLongFrame frame = capture::ReadLatLongFrame(path, capture::RowMappingPolicy::kAccept);
  r.sha256 = Sha256OfFile(path);
  r.radiance = std::move(frame.radiance);
  r.row_mapping = frame.row_mapping;
  if (auto it = frame.extra.strings.find("skycalWarning"); it != frame.extra.strings.end()) {
    r.warnings.push_back(path + ": " + it->second);
  }
  if (auto it = frame.extra.floats.find("skycalTimeOfDay"); it != frame.extra.floats.end()) {
    if (!(it->second >= 0.0f && it->second < 24.0f)) {  // the file's fault, not a --time the user never gave
      throw Error(path + ": attribute 'skycalTimeOfDay' = " + FormatNumber(it->second) + ": expected hours in [0, 24)");
    }
    r.time_of_day_h = it->second;
  }
  const int w = r.radiance.width, h = r.radiance.height;
  SetSunDirection(path, o, frame, &r);
  const std::vector<float> user = ReadUserMask(o, w, h);
  r.clip_level = FindClipLevel(r.radiance);
  ClassifyPixels(o, user, &r);
  if (r.counts.sky == 0) {
    throw Error(path + ": no valid sky pixel to fit (below horizon " + std::to_string(r.counts.below_horizon) +
                ", invalid " + std::to_string(r.counts.invalid) + ", sun cone " + std::to_string(r.counts.sun_cone) +
                ", clipped " + std::to_string(r.counts.clipped) + ", user-masked " + std::to_string(r.counts.user_masked) +
                "; invalid means NaN, infinite, <= 0, or outside [1.2e-38, 1e37] in the file's units)");
  }
  return r;
}

}  // namespace skycal::fit
