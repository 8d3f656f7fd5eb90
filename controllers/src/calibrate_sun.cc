#include "calibrate_sun.h"

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

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
  const int w = frame.width, h = frame.height;
  cv::Mat1f num(h, w, 0.0f), den(h, w, 0.0f);  // sky luminance and sky weight, above 5 deg
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const double Y = capture::Luminance(&frame.pixels[3 * i]);
      if (latlong::ElevationDeg(latlong::PixelDirection(x, y, w, h)) < kMinElevationDeg || !(sky[i] >= 0.5f) ||
          !(Y > 0.0) || !std::isfinite(Y))
        continue;
      num(y, x) = static_cast<float>(Y);
      den(y, x) = 1.0f;
    }
  // Normalised convolution (the mask's edges do not darken the sky beside them); the columns
  // wrap round the seam, the rows reflect at the poles.
  const double sigma_px = kSigmaDeg / 360.0 * w;
  const int pad = std::min(w, static_cast<int>(std::ceil(3.0 * sigma_px)));
  auto blur = [&](const cv::Mat1f& m) {
    cv::Mat1f wrapped, out;
    cv::copyMakeBorder(m, wrapped, 0, 0, pad, pad, cv::BORDER_WRAP);
    cv::GaussianBlur(wrapped, out, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REFLECT);
    return cv::Mat1f(out.colRange(pad, pad + w));
  };
  const cv::Mat1f bn = blur(num), bd = blur(den);
  int best_x = -1, best_y = -1;
  double best = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)  // a pixel of sky, at least half of its neighbourhood sky
      if (den(y, x) > 0.0f && bd(y, x) >= 0.5f && bn(y, x) / bd(y, x) > best) {
        best = bn(y, x) / bd(y, x);
        best_x = x, best_y = y;
      }
  if (best_x < 0) return std::nullopt;
  PhotoSun s;
  s.direction = latlong::PixelDirection(best_x, best_y, w, h);
  s.source = "overcast: nominal, where the deck is brightest";
  s.uncertainty_deg = 90.0;
  return s;
}

}  // namespace skycal::controllers
