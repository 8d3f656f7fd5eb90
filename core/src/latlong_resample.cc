#include "skycal/core/latlong_resample.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "skycal/core/error.h"

namespace skycal {
namespace {

// The input pixels output pixel o covers along one axis: the first and each one's overlap.
struct Span {
  int first = 0;
  std::vector<double> weights;
};

std::vector<Span> Spans(int n, int out_n) {
  std::vector<Span> spans(out_n);
  const double scale = static_cast<double>(n) / out_n;
  for (int o = 0; o < out_n; ++o) {
    const double a = o * scale, b = std::min(static_cast<double>(n), (o + 1) * scale);
    Span& s = spans[o];
    s.first = static_cast<int>(std::floor(a));
    for (int i = s.first; i < n && i < b; ++i) s.weights.push_back(std::min(i + 1.0, b) - std::max(static_cast<double>(i), a));
  }
  return spans;
}

// A pixel whose every channel is positive and finite.
bool Positive(const float* v, int channels) {
  for (int c = 0; c < channels; ++c)
    if (!(v[c] > 0.0f) || !std::isfinite(v[c])) return false;
  return true;
}

std::vector<float> Downsample(const std::vector<float>& values, int width, int height, int channels, int out_width,
                              int out_height, bool positive_only) {
  const std::string sizes = std::to_string(width) + "x" + std::to_string(height) + " to " + std::to_string(out_width) +
                            "x" + std::to_string(out_height);
  if (out_width <= 0 || out_height <= 0 || out_width > width || out_height > height || channels <= 0)
    throw Error("lat-long downsample " + sizes + ": expected a non-empty output no larger than the input");
  if (values.size() != static_cast<size_t>(width) * height * channels)
    throw Error("lat-long downsample " + sizes + ": " + std::to_string(values.size()) + " values for " +
                std::to_string(channels) + " channel(s)");
  const std::vector<Span> xs = Spans(width, out_width), ys = Spans(height, out_height);
  std::vector<float> out(static_cast<size_t>(out_width) * out_height * channels);
  std::vector<double> sum(channels);
  for (int oy = 0; oy < out_height; ++oy)
    for (int ox = 0; ox < out_width; ++ox) {
      std::fill(sum.begin(), sum.end(), 0.0);
      double total = 0.0;
      for (size_t j = 0; j < ys[oy].weights.size(); ++j)
        for (size_t i = 0; i < xs[ox].weights.size(); ++i) {
          const size_t p = (static_cast<size_t>(ys[oy].first + j) * width + xs[ox].first + i) * channels;
          if (positive_only && !Positive(&values[p], channels)) continue;
          const double w = ys[oy].weights[j] * xs[ox].weights[i];
          for (int c = 0; c < channels; ++c) sum[c] += w * values[p + c];
          total += w;
        }
      for (int c = 0; c < channels; ++c)
        out[(static_cast<size_t>(oy) * out_width + ox) * channels + c] =
            total > 0.0 ? static_cast<float>(sum[c] / total) : 0.0f;
    }
  return out;
}

}  // namespace

std::vector<float> AreaDownsampleLatLong(const std::vector<float>& values, int width, int height, int channels,
                                         int out_width, int out_height) {
  return Downsample(values, width, height, channels, out_width, out_height, false);
}

std::vector<float> AreaDownsampleLatLongOfPositive(const std::vector<float>& values, int width, int height, int channels,
                                                   int out_width, int out_height) {
  return Downsample(values, width, height, channels, out_width, out_height, true);
}

}  // namespace skycal
