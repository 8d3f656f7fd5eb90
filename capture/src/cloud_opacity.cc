#include "skycal/capture/cloud_opacity.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"

namespace skycal::capture {
namespace {

using Rgb = std::array<double, 3>;

double Dot(const Rgb& a, const Rgb& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

Rgb PixelOf(const ImageRGB& image, size_t i) {
  return {image.pixels[3 * i], image.pixels[3 * i + 1], image.pixels[3 * i + 2]};
}

bool Positive(const Rgb& c) {
  return std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]) && c[0] >= 0.0 && c[1] >= 0.0 &&
         c[2] >= 0.0 && c[0] + c[1] + c[2] > 0.0;
}

void CheckSizes(const ImageRGB& frame, const ImageRGB& clear, const std::vector<float>& probability,
                const std::vector<float>& sky) {
  const size_t n = static_cast<size_t>(frame.width) * frame.height;
  const auto size = [](int w, int h) { return std::to_string(w) + "x" + std::to_string(h); };
  if (clear.width != frame.width || clear.height != frame.height)
    throw Error("cloud opacity: the clear sky is " + size(clear.width, clear.height) + ", the frame " +
                size(frame.width, frame.height));
  if (probability.size() != n)
    throw Error("cloud opacity: " + std::to_string(probability.size()) + " cloud probabilities for a " +
                size(frame.width, frame.height) + " frame");
  if (!sky.empty() && sky.size() != n)
    throw Error("cloud opacity: a sky mask of " + std::to_string(sky.size()) + " values for a " +
                size(frame.width, frame.height) + " frame");
}

// Per pixel: above the horizon, in the sky, and both colours positive and finite.
std::vector<char> Usable(const ImageRGB& frame, const ImageRGB& clear, const std::vector<float>& sky) {
  const int w = frame.width, h = frame.height;
  std::vector<char> usable(static_cast<size_t>(w) * h, 0);
  for (int y = 0; y < h; ++y) {
    if (latlong::Latitude(y, h) <= 0.0) continue;
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      usable[i] = (sky.empty() || sky[i] >= 0.5f) && Positive(PixelOf(frame, i)) && Positive(PixelOf(clear, i));
    }
  }
  return usable;
}

// The clouds' colour: the per-channel median chromaticity of the sure cloud pixels, renormalised;
// grey when there are fewer than options.min_cloud_pixels.
Rgb CloudColour(const ImageRGB& frame, const std::vector<float>& probability, const std::vector<char>& usable,
                const CloudOpacityOptions& o, long long* count) {
  std::array<std::vector<double>, 3> chroma;
  for (size_t i = 0; i < usable.size(); ++i) {
    if (!usable[i] || !(probability[i] >= o.sure_cloud)) continue;
    const Rgb c = PixelOf(frame, i);
    const double sum = c[0] + c[1] + c[2];
    for (int k = 0; k < 3; ++k) chroma[k].push_back(c[k] / sum);
  }
  *count = static_cast<long long>(chroma[0].size());
  if (*count < o.min_cloud_pixels) {
    *count = 0;
    return {1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
  }
  Rgb w{};
  for (int k = 0; k < 3; ++k) {
    auto mid = chroma[k].begin() + static_cast<long>(chroma[k].size() / 2);
    std::nth_element(chroma[k].begin(), mid, chroma[k].end());
    w[k] = *mid;
  }
  const double sum = w[0] + w[1] + w[2];
  for (double& v : w) v /= sum;
  return w;
}

// T in [0, 1] minimising |L - T S - b w|^2 over b >= 0; false when S and w are too alike.
bool Unmix(const Rgb& l, const Rgb& s, const Rgb& w, double min_separation, double* transmittance) {
  const double ss = Dot(s, s), sw = Dot(s, w), ww = Dot(w, w), ls = Dot(l, s), lw = Dot(l, w);
  const double det = ss * ww - sw * sw;
  if (!(det > min_separation * min_separation * ss * ww)) return false;
  const double t = (ls * ww - lw * sw) / det, b = (ss * lw - sw * ls) / det;
  if (t >= 0.0 && t <= 1.0 && b >= 0.0) {
    *transmittance = t;
    return true;
  }
  // On the boundary of the feasible set: the best of its three edges (the objective is convex).
  const auto cost = [&](double tt, double bb) {
    const Rgb r{l[0] - tt * s[0] - bb * w[0], l[1] - tt * s[1] - bb * w[1], l[2] - tt * s[2] - bb * w[2]};
    return Dot(r, r);
  };
  const double t_b0 = std::clamp(ls / ss, 0.0, 1.0);
  const double b_t0 = std::max(0.0, lw / ww), b_t1 = std::max(0.0, (lw - sw) / ww);
  const double c_b0 = cost(t_b0, 0.0), c_t0 = cost(0.0, b_t0), c_t1 = cost(1.0, b_t1);
  *transmittance = c_b0 <= c_t0 && c_b0 <= c_t1 ? t_b0 : (c_t0 <= c_t1 ? 0.0 : 1.0);
  return true;
}

}  // namespace

bool CloudOpacityOptions::IsValid(std::string* why) const {
  if (!(sure_cloud > 0.0 && sure_cloud <= 1.0)) {
    *why = "CloudOpacityOptions::sure_cloud = " + FormatNumber(sure_cloud) + ": expected (0, 1]";
    return false;
  }
  if (min_cloud_pixels < 1) {
    *why = "CloudOpacityOptions::min_cloud_pixels = " + std::to_string(min_cloud_pixels) + ": expected >= 1";
    return false;
  }
  if (!(min_separation >= 0.0 && min_separation < 1.0)) {
    *why = "CloudOpacityOptions::min_separation = " + FormatNumber(min_separation) + ": expected [0, 1)";
    return false;
  }
  return true;
}

CloudOpacity EstimateCloudOpacity(const ImageRGB& frame, const ImageRGB& clear, const std::vector<float>& probability,
                                  const std::vector<float>& sky, const CloudOpacityOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error("cloud opacity: " + why);
  CheckSizes(frame, clear, probability, sky);
  const std::vector<char> usable = Usable(frame, clear, sky);
  CloudOpacity out;
  const Rgb w = CloudColour(frame, probability, usable, o, &out.colour_pixels);
  out.cloud_colour = w;
  out.opacity.assign(usable.size(), 0.0f);
  for (size_t i = 0; i < usable.size(); ++i) {
    if (!usable[i]) continue;
    double t = 1.0;
    if (Unmix(PixelOf(frame, i), PixelOf(clear, i), w, o.min_separation, &t)) {
      out.opacity[i] = static_cast<float>(1.0 - t);
      ++out.unmixed;
    } else {
      out.opacity[i] = std::clamp(probability[i], 0.0f, 1.0f);
      ++out.from_probability;
    }
  }
  return out;
}

}  // namespace skycal::capture
