// Finding a ColorChecker in an image (OpenCV mcc) and measuring its patches in linear RGB.
#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/mcc.hpp>

#include "skycal/capture/color_chart.h"
#include "skycal/capture/hdr_merge.h"
#include "skycal/capture/raw_decode.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/luminance.h"

namespace skycal::capture {
namespace {

// The ColorChecker Classic's layout in the units of OpenCV mcc's chart model: 6 x 4 patches
// of 2.5 with gaps (and a border) of 0.25, 16.75 x 11.25 in all.
constexpr double kPatchSide = 2.5, kGap = 0.25, kChartW = 16.75, kChartH = 11.25;

bool EndsWith(const std::string& s, const std::string& e) {
  if (s.size() < e.size()) return false;
  return std::equal(e.rbegin(), e.rend(), s.rbegin(), [](char a, char b) { return std::tolower(a) == std::tolower(b); });
}

ChartImage LoadExrChart(const std::string& path) {
  ExrRGB exr = ReadExrRGB(path);
  ChartImage out{path, std::move(exr.image), {}};
  const size_t n = static_cast<size_t>(out.linear.width) * out.linear.height;
  out.clipped.assign(n, 0);
  std::vector<float> valid;
  if (std::find(exr.channels.begin(), exr.channels.end(), "mask.valid") != exr.channels.end()) {
    int w = 0, h = 0;
    valid = ReadExrChannel(path, "mask.valid", &w, &h);
  }
  float top = 0.0f;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      if (std::isfinite(out.linear.pixels[3 * i + c])) top = std::max(top, out.linear.pixels[3 * i + c]);
  size_t at_top = 0;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) at_top += out.linear.pixels[3 * i + c] == top;
  for (size_t i = 0; i < n; ++i) {
    bool bad = !valid.empty() && valid[i] < 0.5f;
    for (int c = 0; c < 3; ++c) {
      const float v = out.linear.pixels[3 * i + c];
      bad = bad || !std::isfinite(v) || (at_top > 1 && v == top);  // a plateau of the maximum: clamped
    }
    out.clipped[i] = bad;
  }
  return out;
}

}  // namespace

ChartImage LoadChartImage(const std::string& path, const std::vector<float>& response_curve) {
  if (EndsWith(path, ".exr")) return LoadExrChart(path);
  // A camera RAW chart is linear by construction (raw_decode.h): no curve, its saturation
  // mask marks the clipped pixels.
  const bool raw = IsRawPath(path);
  const BracketImage img = raw ? ReadRawImage(path).image : ReadBracketImage(path);
  const int top = img.max_code();
  const int levels = response_curve.empty() || raw ? 0 : static_cast<int>(response_curve.size() / 3);
  if (!raw && !response_curve.empty() && (response_curve.size() % 3 != 0 || levels < 2)) {
    throw Error(path + ": response curve of " + std::to_string(response_curve.size()) + " values; expected levels x 3");
  }
  ChartImage out{path, ImageRGB(img.width, img.height), std::vector<uint8_t>(static_cast<size_t>(img.width) * img.height, 0)};
  for (size_t i = 0; i < out.clipped.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const int code = img.rgb[3 * i + c];
      double v = static_cast<double>(code) / top;
      if (levels > 0) {  // the curve's codes spread over 0..top (a 256-level curve on 16-bit codes)
        const double x = v * (levels - 1);
        const int k = std::min(levels - 2, static_cast<int>(x));
        const double f = x - k;
        v = (1.0 - f) * response_curve[3 * k + c] + f * response_curve[3 * (k + 1) + c];
      }
      out.linear.pixels[3 * i + c] = static_cast<float>(v);
      if (code >= top || (!img.saturated.empty() && img.saturated[i])) out.clipped[i] = 1;
    }
  }
  return out;
}

bool ChartOptions::IsValid(std::string* why) const {
  if (!(patch_fraction > 0.05 && patch_fraction <= 1.0)) {
    *why = "patch_fraction: expected (0.05, 1], got " + std::to_string(patch_fraction);
    return false;
  }
  if (min_patch_pixels < 1) {
    *why = "min_patch_pixels: expected >= 1";
    return false;
  }
  if (!(max_clipped_fraction >= 0.0 && max_clipped_fraction < 1.0)) {
    *why = "max_clipped_fraction: expected [0, 1)";
    return false;
  }
  if (corners) {
    for (double v : *corners) {
      if (!std::isfinite(v)) {
        *why = "corners: expected 8 finite pixel coordinates";
        return false;
      }
    }
  }
  return true;
}

namespace {

struct Sampled {
  ChartColors mean{};
  std::array<int, kChartPatches> pixels{}, clipped{};
  std::array<double, kChartPatches> spread{};  // variance of ln(luminance) in the square
};

// Means (and spreads) of each patch's central square, through the homography chart units -> pixels.
Sampled SamplePatches(const ChartImage& img, const std::array<double, 8>& corners, double fraction) {
  const cv::Point2f unit[4] = {{0.0f, 0.0f}, {float(kChartW), 0.0f}, {float(kChartW), float(kChartH)}, {0.0f, float(kChartH)}};
  cv::Point2f px[4];
  for (int k = 0; k < 4; ++k) px[k] = {float(corners[2 * k]), float(corners[2 * k + 1])};
  const cv::Matx33d to_px(cv::getPerspectiveTransform(unit, px));
  const cv::Matx33d to_unit = to_px.inv();
  auto map = [](const cv::Matx33d& h, double x, double y) {
    const cv::Vec3d v = h * cv::Vec3d(x, y, 1.0);
    return cv::Point2d(v[0] / v[2], v[1] / v[2]);
  };
  Sampled s;
  const double margin = 0.5 * kPatchSide * (1.0 - fraction);
  for (int p = 0; p < kChartPatches; ++p) {
    const int row = p / 6, col = p % 6;
    const double u0 = kGap + col * (kPatchSide + kGap) + margin, u1 = u0 + kPatchSide - 2.0 * margin;
    const double v0 = kGap + row * (kPatchSide + kGap) + margin, v1 = v0 + kPatchSide - 2.0 * margin;
    double x_lo = 1e30, x_hi = -1e30, y_lo = 1e30, y_hi = -1e30;
    for (const auto& [u, v] : {std::pair{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}}) {
      const cv::Point2d q = map(to_px, u, v);
      x_lo = std::min(x_lo, q.x), x_hi = std::max(x_hi, q.x), y_lo = std::min(y_lo, q.y), y_hi = std::max(y_hi, q.y);
    }
    Rgb sum{0, 0, 0};
    double sum_l = 0.0, sum_l2 = 0.0;
    for (int y = std::max(0, int(std::floor(y_lo))); y <= std::min(img.linear.height - 1, int(std::ceil(y_hi))); ++y) {
      for (int x = std::max(0, int(std::floor(x_lo))); x <= std::min(img.linear.width - 1, int(std::ceil(x_hi))); ++x) {
        const cv::Point2d q = map(to_unit, x, y);
        if (q.x < u0 || q.x > u1 || q.y < v0 || q.y > v1) continue;
        const size_t i = static_cast<size_t>(y) * img.linear.width + x;
        ++s.pixels[p];
        s.clipped[p] += img.clipped[i];
        for (int c = 0; c < 3; ++c) sum[c] += img.linear.pixels[3 * i + c];
        const float* rgb = &img.linear.pixels[3 * i];
        const double l = std::log(std::max(1e-12, Rec709Luminance<double>(rgb[0], rgb[1], rgb[2])));
        sum_l += l, sum_l2 += l * l;
      }
    }
    if (s.pixels[p] > 0) s.spread[p] = sum_l2 / s.pixels[p] - (sum_l / s.pixels[p]) * (sum_l / s.pixels[p]);
    for (int c = 0; c < 3; ++c) s.mean[p][c] = s.pixels[p] > 0 ? sum[c] / s.pixels[p] : 0.0;
  }
  return s;
}

double CameraY(const Rgb& c) { return Rec709Luminance(c); }

// White to black: each neutral patch darker than the one before (a cast scales them alike).
bool NeutralsOrdered(const ChartColors& m) {
  for (int i = 19; i < 24; ++i)
    if (!(CameraY(m[i]) < CameraY(m[i - 1]))) return false;
  return true;
}

// The image as OpenCV mcc wants it (8-bit BGR), exposed by `gain` and sRGB-encoded.
cv::Mat EightBit(const ImageRGB& img, double gain) {
  cv::Mat out(img.height, img.width, CV_8UC3);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      cv::Vec3b& o = out.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) {
        const double v = img.at(x, y, c) * gain;
        const double e = std::isfinite(v) ? SrgbEncode(std::clamp(v, 0.0, 1.0)) : 0.0;
        o[2 - c] = static_cast<uint8_t>(std::lround(255.0 * e));
      }
    }
  }
  return out;
}

// The 99th percentile of the pixels' largest channel: the detection exposures' reference.
double BrightReference(const ImageRGB& img) {
  std::vector<float> m;
  m.reserve(img.pixels.size() / 3);
  for (size_t i = 0; i + 2 < img.pixels.size(); i += 3) {
    const float v = std::max({img.pixels[i], img.pixels[i + 1], img.pixels[i + 2]});
    if (std::isfinite(v) && v > 0.0f) m.push_back(v);
  }
  if (m.empty()) return 0.0;
  const size_t k = static_cast<size_t>(0.99 * (m.size() - 1));
  std::nth_element(m.begin(), m.begin() + k, m.end());
  return m[k];
}

std::string PatchLabel(int p) { return "patch " + std::to_string(p + 1) + " (" + ColorCheckerPatchName(p) + ")"; }

// Checks a sampled chart: enough pixels, nothing clipped. Throws naming the image.
void CheckSamples(const ChartImage& img, const Sampled& s, const ChartOptions& o) {
  for (int p = 0; p < kChartPatches; ++p) {
    if (s.pixels[p] < o.min_patch_pixels) {
      throw Error(img.path + ": colour chart " + PatchLabel(p) + " covers " + std::to_string(s.pixels[p]) +
                  " pixels in its central square; expected at least " + std::to_string(o.min_patch_pixels) +
                  " (the chart is too small in the image, or its corners are wrong)");
    }
  }
  for (int p = 0; p < kChartPatches; ++p) {
    const double f = static_cast<double>(s.clipped[p]) / s.pixels[p];
    if (f > o.max_clipped_fraction) {
      throw Error(img.path + ": colour chart " + PatchLabel(p) + " is clipped: " + std::to_string(int(std::lround(100 * f))) +
                  "% of its pixels at full scale (at most " + std::to_string(100 * o.max_clipped_fraction) +
                  "% allowed); use an exposure in which the chart's white is below full scale");
    }
  }
}

// Spread of the patches' central squares: the sum over patches of the variance of log
// luminance (a square that straddles a gap or a neighbour is not uniform).
double PatchSpread(const ChartImage& img, const std::array<double, 8>& corners, double fraction) {
  const Sampled s = SamplePatches(img, corners, fraction);
  double sum = 0.0;
  for (int p = 0; p < kChartPatches; ++p) sum += s.pixels[p] > 1 ? s.spread[p] : 1e3;
  return sum;
}

// OpenCV mcc's box is good to a few pixels (up to 5 at 12 px patches, measured), enough to
// put a patch's central square partly on the black gap: refine it by the shift (whole
// pixels, +-4) and scale (+-4%) about its centre, then each corner, whichever make the
// patches most uniform.
std::array<double, 8> RefineCorners(const ChartImage& img, const std::array<double, 8>& c, double fraction) {
  const double cx = 0.25 * (c[0] + c[2] + c[4] + c[6]), cy = 0.25 * (c[1] + c[3] + c[5] + c[7]);
  std::array<double, 8> best = c;
  double best_spread = PatchSpread(img, c, fraction);
  for (const double scale : {0.96, 0.98, 1.0, 1.02, 1.04})
    for (int dy = -4; dy <= 4; ++dy)
      for (int dx = -4; dx <= 4; ++dx) {
        std::array<double, 8> t{};
        for (int k = 0; k < 4; ++k) {
          t[2 * k] = cx + scale * (c[2 * k] - cx) + dx;
          t[2 * k + 1] = cy + scale * (c[2 * k + 1] - cy) + dy;
        }
        const double spread = PatchSpread(img, t, fraction);
        if (spread < best_spread) best_spread = spread, best = t;
      }
  // Then each corner on its own (mcc's box can be skewed: up to 5 px at one corner and the
  // opposite way at the next, measured), two passes of +-3 px.
  for (int pass = 0; pass < 2; ++pass)
    for (int k = 0; k < 4; ++k) {
      const std::array<double, 8> start = best;
      for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx) {
          std::array<double, 8> t = start;
          t[2 * k] += dx, t[2 * k + 1] += dy;
          const double spread = PatchSpread(img, t, fraction);
          if (spread < best_spread) best_spread = spread, best = t;
        }
    }
  return best;
}

}  // namespace

ChartDetection FindColorChecker(const ChartImage& img, const ChartOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(img.path + ": chart options: " + why);
  ChartDetection d;
  if (o.corners) {
    for (int k = 0; k < 4; ++k) {
      const double x = (*o.corners)[2 * k], y = (*o.corners)[2 * k + 1];
      if (x < 0 || y < 0 || x > img.linear.width - 1 || y > img.linear.height - 1) {
        throw Error(img.path + ": chart corner " + std::to_string(k + 1) + " (" + std::to_string(x) + ", " +
                    std::to_string(y) + ") is outside the " + std::to_string(img.linear.width) + "x" +
                    std::to_string(img.linear.height) + " image");
      }
    }
    d.corners = *o.corners;
    d.method = "user corners";
    const Sampled s = SamplePatches(img, d.corners, o.patch_fraction);
    CheckSamples(img, s, o);
    if (!NeutralsOrdered(s.mean)) {
      throw Error(img.path + ": the chart corners given do not put the neutral patches 19-24 in order white to black; "
                  "expected the corner at patch 1 (dark skin) first, then clockwise (patches 6, 24, 19)");
    }
    d.patches = s.mean;
    d.pixels = s.pixels;
    return d;
  }
  const double bright = BrightReference(img.linear);
  if (!(bright > 0.0)) throw Error(img.path + ": no colour chart found: the image has no positive pixel");
  auto detector = cv::mcc::CCheckerDetector::create();
  std::string tried;
  for (const double ev : {0.0, 2.0, -2.0, 4.0, 6.0, 8.0, -4.0}) {
    tried += (tried.empty() ? "" : ", ") + std::to_string(int(ev));
    if (!detector->process(EightBit(img.linear, std::exp2(ev) / bright), cv::mcc::MCC24, 1)) continue;
    const std::vector<cv::Point2f> box = detector->getBestColorChecker()->getBox();
    if (box.size() != 4) continue;
    for (int k = 0; k < 4; ++k) d.corners[2 * k] = box[k].x, d.corners[2 * k + 1] = box[k].y;
    d.corners = RefineCorners(img, d.corners, o.patch_fraction);
    const Sampled s = SamplePatches(img, d.corners, o.patch_fraction);
    if (!NeutralsOrdered(s.mean)) continue;  // a false or mis-oriented detection
    CheckSamples(img, s, o);
    d.method = "mcc";
    d.detection_ev = ev;
    d.patches = s.mean;
    d.pixels = s.pixels;
    return d;
  }
  throw Error(img.path + ": no ColorChecker 24 chart found (OpenCV mcc on the image exposed at " + tried +
              " EV from its 99th percentile); give the chart's corners (--chart-corners X1,Y1,...,X4,Y4: the corner at "
              "patch 1, dark skin, first, then clockwise)");
}

}  // namespace skycal::capture
