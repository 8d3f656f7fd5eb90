#include "skycal/capture/sky_kind.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"

namespace skycal::capture {
namespace {

constexpr double kZenithCapDeg = 45.0;  // "zenith" statistics: the sky above this elevation
constexpr double kTextureSigmaPx = 1.5; // Gaussian of the texture residual (the segmentation's scale), at:
constexpr int kTextureWidth = 512;      // the lat-long width (pixels) the texture is measured at
constexpr double kPointMinDeg = 20.0;   // stars counted above this elevation (away from lamps and haze)
constexpr float kPointContrast = 0.1f;  // ln Y above every neighbour: a point source (a star), not a cloud edge
constexpr float kTiny = 1e-12f;         // below: not a valid radiance (a black or clipped-to-zero pixel)

bool Range(std::string* why, const char* field, double v, double lo, double hi, bool open = false) {
  const bool ok = std::isfinite(v) && (open ? (v > lo && v < hi) : (v >= lo && v <= hi));
  if (!ok && why) {
    *why = std::string("SkyKindOptions::") + field + " = " + FormatNumber(v) + " (expected " + (open ? "(" : "[") +
           FormatNumber(lo) + ", " + FormatNumber(hi) + (open ? ")" : "]") + ")";
  }
  return ok;
}

// The element of rank k (0-based) of v; NaN when v is empty.
double AtRank(std::vector<double> v, size_t k) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double Median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  return AtRank(std::move(v), mid);
}

// The q-quantile of v: the element at rank q (n - 1), no interpolation.
double Quantile(const std::vector<double>& v, double q) {
  return AtRank(v, v.empty() ? 0 : static_cast<size_t>(q * static_cast<double>(v.size() - 1)));
}

// ln Y per pixel of the upper half (rows above the horizon), invalid pixels set to the
// row's valid mean so the blur does not spread them; `valid` marks the real ones.
cv::Mat UpperLogLuminance(const ImageRGB& f, int rows, cv::Mat* valid) {
  cv::Mat ln(rows, f.width, CV_32F, cv::Scalar(0.0f));
  *valid = cv::Mat(rows, f.width, CV_8U, cv::Scalar(0));
  for (int y = 0; y < rows; ++y) {
    double sum = 0.0;
    int n = 0;
    for (int x = 0; x < f.width; ++x) {
      const float Y = Rec709Luminance(f.at(x, y, 0), f.at(x, y, 1), f.at(x, y, 2));
      if (!(Y > kTiny) || !std::isfinite(Y)) continue;
      ln.at<float>(y, x) = std::log(Y);
      valid->at<uint8_t>(y, x) = 1;
      sum += std::log(Y);
      ++n;
    }
    for (int x = 0; x < f.width && n > 0; ++x)
      if (!valid->at<uint8_t>(y, x)) ln.at<float>(y, x) = static_cast<float>(sum / n);
  }
  return ln;
}

// The local variance of ln Y about its Gaussian blur, measured at kTextureWidth (a fixed
// angular scale: a smooth sky's residual grows with the square of the pixel's angle, so a
// thumbnail of a clear sky would otherwise read as textured), returned at ln's size.
cv::Mat TextureVariance(const cv::Mat& ln) {
  cv::Mat at_scale = ln;
  if (ln.cols != kTextureWidth) {
    const int rows = std::max(1, static_cast<int>(std::lround(static_cast<double>(ln.rows) * kTextureWidth / ln.cols)));
    cv::resize(ln, at_scale, cv::Size(kTextureWidth, rows), 0, 0, ln.cols > kTextureWidth ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  cv::Mat blur, residual2, rms;
  cv::GaussianBlur(at_scale, blur, cv::Size(0, 0), kTextureSigmaPx, kTextureSigmaPx, cv::BORDER_REFLECT);
  cv::multiply(at_scale - blur, at_scale - blur, residual2);
  cv::GaussianBlur(residual2, rms, cv::Size(0, 0), kTextureSigmaPx, kTextureSigmaPx, cv::BORDER_REFLECT);
  if (ln.cols == kTextureWidth) return rms;
  cv::Mat back;
  cv::resize(rms, back, ln.size(), 0, 0, cv::INTER_LINEAR);
  return back;
}

// Share of the valid sky pixels above kPointMinDeg that are strict local maxima of ln Y,
// kPointContrast above each of their 8 neighbours (longitude wraps).
double PointSourceShare(const cv::Mat& ln, const cv::Mat& valid, const std::vector<float>& sky, int height) {
  long long peaks = 0, total = 0;
  const int w = ln.cols;
  for (int y = 1; y + 1 < ln.rows; ++y) {
    if (latlong::Latitude(y, height) * 180.0 / kPi < kPointMinDeg) break;
    for (int x = 0; x < w; ++x) {
      if (!(sky[static_cast<size_t>(y) * w + x] >= 0.5f) || !valid.at<uint8_t>(y, x)) continue;
      ++total;
      const float c = ln.at<float>(y, x);
      bool peak = true;
      for (int dy = -1; dy <= 1 && peak; ++dy)
        for (int dx = -1; dx <= 1 && peak; ++dx)
          if ((dx || dy) && !(c - ln.at<float>(y + dy, (x + dx + w) % w) >= kPointContrast)) peak = false;
      peaks += peak;
    }
  }
  return total > 0 ? static_cast<double>(peaks) / static_cast<double>(total) : 0.0;
}

}  // namespace

const char* ToString(SkyKind kind) {
  switch (kind) {
    case SkyKind::kClear: return "clear";
    case SkyKind::kPartlyCloudy: return "partly cloudy";
    case SkyKind::kOvercast: return "overcast";
    case SkyKind::kTwilight: return "twilight";
    case SkyKind::kNight: return "night";
    case SkyKind::kNotSky: return "not a sky";
  }
  return "?";
}

bool SkyKindOptions::IsValid(std::string* why) const {
  return Range(why, "min_sky_share", min_sky_share, 0.0, 1.0, true) &&
         Range(why, "min_zenith_sky_share", min_zenith_sky_share, 0.0, 1.0, true) &&
         Range(why, "lamp_blue", lamp_blue, -3.0, 0.0) &&
         Range(why, "night_sun_deg", night_sun_deg, -30.0, 0.0) &&
         Range(why, "twilight_sun_deg", twilight_sun_deg, -10.0, 5.0) &&
         Range(why, "night_points", night_points, 0.0, 1.0, true) &&
         Range(why, "night_blue", night_blue, -2.0, 2.0) &&
         Range(why, "overcast_cloud_share", overcast_cloud_share, 0.0, 1.0 + 1e-12, true) &&
         Range(why, "overcast_blue", overcast_blue, -1.0, 2.0) &&
         Range(why, "cloudy_texture", cloudy_texture, 0.0, 10.0, true) &&
         Range(why, "cloudy_texture_q75", cloudy_texture_q75, 0.0, 10.0, true) &&
         (night_sun_deg < twilight_sun_deg || Range(why, "night_sun_deg", night_sun_deg, -30.0, twilight_sun_deg, true));
}

SkyFeatures MeasureSkyFeatures(const ImageRGB& f, const std::vector<float>& sky, const std::vector<float>& cloud_probability,
                               std::optional<double> sun_elevation_deg) {
  const size_t n = static_cast<size_t>(f.width) * static_cast<size_t>(f.height);
  if (f.empty() || sky.size() != n) throw Error("sky kind: the sky mask has " + std::to_string(sky.size()) +
                                                " pixels, the frame " + std::to_string(n));
  if (!cloud_probability.empty() && cloud_probability.size() != n)
    throw Error("sky kind: the cloud probability has " + std::to_string(cloud_probability.size()) + " pixels, the frame " +
                std::to_string(n));
  int rows = 0;  // rows strictly above the horizon
  while (rows < f.height && latlong::Latitude(rows, f.height) > 0.0) ++rows;
  cv::Mat valid;
  const cv::Mat ln = UpperLogLuminance(f, rows, &valid);
  const cv::Mat rms = TextureVariance(ln);
  double sky_w = 0.0, all_w = 0.0, cloud = 0.0, cloud_w = 0.0, cap_sky_w = 0.0, cap_w = 0.0;
  std::vector<double> blue, texture, lum;
  for (int y = 0; y < rows; ++y) {
    const bool cap = latlong::Latitude(y, f.height) * 180.0 / kPi >= kZenithCapDeg;
    for (int x = 0; x < f.width; ++x) {
      const size_t i = static_cast<size_t>(y) * f.width + x;
      const double w = latlong::PixelSolidAngle(x, y, f.width, f.height);
      all_w += w;
      cap_w += cap ? w : 0.0;
      if (!(sky[i] >= 0.5f)) continue;
      sky_w += w;
      cap_sky_w += cap ? w : 0.0;
      if (!valid.at<uint8_t>(y, x)) continue;
      const float r = f.at(x, y, 0), b = f.at(x, y, 2);
      if (cap && r > kTiny && b > kTiny) blue.push_back(std::log(b / r));
      texture.push_back(std::sqrt(std::max(0.0f, rms.at<float>(y, x))));
      lum.push_back(std::exp(ln.at<float>(y, x)));
      if (!cloud_probability.empty()) {
        cloud += w * cloud_probability[i];
        cloud_w += w;
      }
    }
  }
  SkyFeatures out;
  out.point_sources = PointSourceShare(ln, valid, sky, f.height);
  out.sky_share = all_w > 0.0 ? sky_w / all_w : 0.0;
  out.zenith_sky_share = cap_w > 0.0 ? cap_sky_w / cap_w : 0.0;
  out.zenith_blue = Median(std::move(blue));
  out.texture_q75 = Quantile(texture, 0.75);
  out.texture = Median(std::move(texture));
  out.sky_luminance = Median(std::move(lum));
  out.cloud_share = cloud_w > 0.0 ? cloud / cloud_w : std::numeric_limits<double>::quiet_NaN();
  out.sun_elevation_deg = sun_elevation_deg;
  return out;
}

bool HasCloudEdges(const SkyFeatures& s, const SkyKindOptions& o) {
  return s.texture >= o.cloudy_texture || s.texture_q75 >= o.cloudy_texture_q75;
}

SkyKindDecision ClassifySky(const SkyFeatures& s, const SkyKindOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const auto F = [](double v) { return FormatNumber(std::round(v * 1e4) / 1e4); };
  const bool grey = std::isfinite(s.zenith_blue) && s.zenith_blue < o.overcast_blue;
  if (!(s.sky_share >= o.min_sky_share))
    return {SkyKind::kNotSky, "sky share " + F(s.sky_share) + " of the upper hemisphere < min_sky_share " +
                                  F(o.min_sky_share) + " (a canopy, an interior, or a street)"};
  if (!(s.zenith_sky_share >= o.min_zenith_sky_share))
    return {SkyKind::kNotSky, "the zenith is covered: sky share " + F(s.zenith_sky_share) + " above 45 deg < " +
                                  "min_zenith_sky_share " + F(o.min_zenith_sky_share) + " (a roof or a canopy overhead)"};
  if (std::isfinite(s.zenith_blue) && s.zenith_blue < o.lamp_blue)
    return {SkyKind::kNotSky, "the 'sky' overhead is redder than any sky: zenith ln(B/R) " + F(s.zenith_blue) +
                                  " < lamp_blue " + F(o.lamp_blue) + " (a ceiling under lamps: an interior)"};
  if (s.sun_elevation_deg && *s.sun_elevation_deg <= o.night_sun_deg)
    return {SkyKind::kNight, "sun elevation " + F(*s.sun_elevation_deg) + " deg <= night_sun_deg " + F(o.night_sun_deg)};
  const bool sun_known_up = s.sun_elevation_deg && *s.sun_elevation_deg > o.twilight_sun_deg && !s.sun_from_disc;
  if (!sun_known_up && s.point_sources >= o.night_points && std::isfinite(s.zenith_blue) && s.zenith_blue < o.night_blue)
    return {SkyKind::kNight, "stars: point-source share " + F(s.point_sources * 1e4) + "e-4 >= night_points " +
                                 F(o.night_points * 1e4) + "e-4 under a zenith of ln(B/R) " + F(s.zenith_blue) +
                                 " < night_blue " + F(o.night_blue)};
  if (s.sun_elevation_deg && *s.sun_elevation_deg < o.twilight_sun_deg)
    return {SkyKind::kTwilight, "sun elevation " + F(*s.sun_elevation_deg) + " deg < twilight_sun_deg " +
                                    F(o.twilight_sun_deg) + " (and above night_sun_deg " + F(o.night_sun_deg) + ")"};
  const bool edges = HasCloudEdges(s, o);
  const std::string no_edges = ", texture " + F(s.texture) + " < cloudy_texture " + F(o.cloudy_texture) +
                               " and its upper quartile " + F(s.texture_q75) + " < cloudy_texture_q75 " +
                               F(o.cloudy_texture_q75);
  if (std::isfinite(s.cloud_share) && s.cloud_share >= o.overcast_cloud_share && !edges)
    return {SkyKind::kOvercast, "cloud share " + F(s.cloud_share) + " >= overcast_cloud_share " + F(o.overcast_cloud_share) +
                                    no_edges + " (one deck)"};
  if (grey && !edges)
    return {SkyKind::kOvercast, "a grey, uniform sky: zenith ln(B/R) " + F(s.zenith_blue) + " < overcast_blue " +
                                    F(o.overcast_blue) + no_edges};
  if (s.texture >= o.cloudy_texture)
    return {SkyKind::kPartlyCloudy, "cloud edges: texture " + F(s.texture) + " >= cloudy_texture " + F(o.cloudy_texture)};
  if (s.texture_q75 >= o.cloudy_texture_q75)
    return {SkyKind::kPartlyCloudy, "cloud edges over a quarter of the sky: texture's upper quartile " + F(s.texture_q75) +
                                        " >= cloudy_texture_q75 " + F(o.cloudy_texture_q75) + " (its median " + F(s.texture) +
                                        ": a clear sky without noise between them)"};
  return {SkyKind::kClear, no_edges.substr(2) + ", zenith ln(B/R) " + F(s.zenith_blue) + " >= overcast_blue " +
                               F(o.overcast_blue)};
}

}  // namespace skycal::capture
