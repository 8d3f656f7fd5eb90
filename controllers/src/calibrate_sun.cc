#include "calibrate_sun.h"

#include <cmath>

#include "skycal/capture/solar_position.h"
#include "skycal/capture/sun_detect.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/skysun/sky_sun.h"

namespace skycal::controllers {
namespace {

std::string Deg(double v) { return FormatNumber(std::round(v * 100.0) / 100.0) + " deg"; }

// The time and place's sun: its elevation, and its azimuth from north when the frame's
// north is known, else from the sky's estimate (its azimuth uncertainty carried).
std::optional<PhotoSun> SunOfTimeAndPlace(const std::optional<skysun::SkySunEstimate>& sky_sun,
                                          const CalibrateOptions& o, std::string* why) {
  capture::SpaInput in = capture::ParseIso8601(*o.time_iso8601, "CalibrateOptions::time_iso8601");
  in.latitude_deg = *o.latitude_deg;
  in.longitude_deg = *o.longitude_deg;
  const capture::SpaResult spa = capture::ComputeSolarPosition(in);
  PhotoSun s;
  if (o.north_longitude_deg) {
    s.direction = capture::SunDirectionInFrame(spa, *o.north_longitude_deg);
    s.source = "time and place";
    return s;
  }
  if (!sky_sun) {
    *why = "the time and place give the elevation " + Deg(spa.elevation_deg) +
           " but not the azimuth (no north_longitude_deg, and the sky does not place it)";
    return std::nullopt;
  }
  s.direction = latlong::DirectionFromElevationAzimuthDeg(spa.elevation_deg, sky_sun->azimuth_deg);
  s.source = "time and place, azimuth from the sky";
  s.uncertainty_deg = sky_sun->azimuth_uncertainty_deg;
  return s;
}

}  // namespace

PhotoSun PlainPhotoSun(const ImageRGB& frame, const std::optional<std::array<double, 3>>& file_sun,
                       const CalibrateOptions& o) {
  PhotoSun s;
  if (o.sun_elevation_deg) {
    s.direction = latlong::DirectionFromElevationAzimuthDeg(*o.sun_elevation_deg, *o.sun_azimuth_deg);
    s.source = "option";
  } else if (file_sun) {
    s.direction = *file_sun;
    s.source = "attribute";
  } else if (const auto disc = capture::DetectSun(frame, &s.refusal, kCalibrateDiscContrast)) {
    s.direction = disc->direction;
    s.source = "disc";
  } else {
    s.refusal = "no sun disc (" + s.refusal + ")";
  }
  return s;
}

PhotoSun HiddenPhotoSun(const ImageRGB& frame, const std::vector<float>& sky, const CalibrateOptions& o,
                        const std::string& no_disc) {
  std::string no_sky, no_time;
  std::optional<skysun::SkySunEstimate> sky_sun;
  try {
    sky_sun = skysun::EstimateSunFromSky(frame, sky, {}, &no_sky);
  } catch (const std::exception& e) {  // too few sky cells: no estimate, the reason kept
    no_sky = e.what();
  }
  if (o.time_iso8601) {
    if (auto t = SunOfTimeAndPlace(sky_sun, o, &no_time)) return *t;
  }
  PhotoSun s;
  if (sky_sun) {
    s.direction = sky_sun->direction;
    s.source = "sky";
    s.uncertainty_deg = sky_sun->uncertainty_deg;
    return s;
  }
  s.refusal = no_disc + "; the sky does not place the sun (" + no_sky + ")" + (no_time.empty() ? std::string("") : "; " + no_time);
  return s;
}

PhotoSun ChoosePhotoSun(const ImageRGB& frame, const std::vector<float>& sky,
                        const std::optional<std::array<double, 3>>& file_sun, const CalibrateOptions& o) {
  const PhotoSun plain = PlainPhotoSun(frame, file_sun, o);
  return plain.direction ? plain : HiddenPhotoSun(frame, sky, o, plain.refusal);
}

std::optional<PhotoSun> NominalOvercastSun(const ImageRGB& frame, const std::vector<float>& sky) {
  constexpr double kSigmaDeg = 5.0, kMinElevationDeg = 5.0;
  const auto patch = capture::BrightestSkyPatch(frame, sky, kSigmaDeg, kMinElevationDeg);
  if (!patch) return std::nullopt;
  PhotoSun s;
  s.direction = *patch;
  s.source = "overcast: nominal, where the deck is brightest";
  s.uncertainty_deg = 90.0;
  return s;
}

}  // namespace skycal::controllers
