#include "skycal/capture/sky_segmentation.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "latlong_blur.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"

namespace skycal::capture {
namespace {

bool InRange(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

bool Fail(std::string* why, const std::string& field, double value, const std::string& expected) {
  *why = "SkyMaskOptions::" + field + " = " + FormatNumber(value) + " (expected " + expected + ")";
  return false;
}

// A pixel every cue can take the logarithm of: each channel finite and positive.
bool ValidPixel(const ImageRGB& f, int x, int y) {
  const float r = f.at(x, y, 0), g = f.at(x, y, 1), b = f.at(x, y, 2);
  return std::isfinite(r) && std::isfinite(g) && std::isfinite(b) && r > 0.0f && g > 0.0f && b > 0.0f;
}

// Log luminance of the rows above the horizon; invalid pixels (NaN, Inf, <= 0) filled by a
// normalised blur of their valid neighbours (a few passes; what is left takes the band's
// median).
cv::Mat LogLuminance(const ImageRGB& f, int rows, cv::Mat* valid_out) {
  cv::Mat L(rows, f.width, CV_32F), valid(rows, f.width, CV_32F);
  std::vector<float> good;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < f.width; ++x) {
      const bool ok = ValidPixel(f, x, y);
      L.at<float>(y, x) = ok ? std::log(Rec709Luminance(f.at(x, y, 0), f.at(x, y, 1), f.at(x, y, 2))) : 0.0f;
      valid.at<float>(y, x) = ok ? 1.0f : 0.0f;
      if (ok) good.push_back(L.at<float>(y, x));
    }
  }
  *valid_out = valid.clone();
  if (good.empty()) return cv::Mat(rows, f.width, CV_32F, cv::Scalar(0.0f));
  std::nth_element(good.begin(), good.begin() + good.size() / 2, good.end());
  const float median = good[good.size() / 2];
  cv::Mat known = valid.clone();
  for (int pass = 0; pass < 4; ++pass) {
    const cv::Mat num = BlurWrapped(L.mul(known), 2.0), den = BlurWrapped(known, 2.0);
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < f.width; ++x)
        if (known.at<float>(y, x) == 0.0f && den.at<float>(y, x) > 1e-3f) {
          L.at<float>(y, x) = num.at<float>(y, x) / den.at<float>(y, x);
          known.at<float>(y, x) = 1.0f;
        }
  }
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < f.width; ++x)
      if (known.at<float>(y, x) == 0.0f) L.at<float>(y, x) = median;
  return L;
}

// The sky's reference log luminance per pixel: the `quantile` of the row's values within an
// azimuth window around each of 24 sector centres, interpolated linearly between centres
// (wrapping). Then, going down from the zenith, a row's reference may fall below the one a
// row above by at most `max_drop_per_row` (the sky darkens toward the horizon slowly; a row
// filled with buildings would otherwise take the buildings as its sky).
cv::Mat SkyReference(const cv::Mat& L, double quantile, double window_deg, double max_drop_per_row) {
  constexpr int kSectors = 24;
  const int w = L.cols, rows = L.rows;
  const int half = std::max(1, static_cast<int>(std::lround(window_deg / 360.0 * w / 2.0)));
  cv::Mat sector_ref(rows, kSectors, CV_32F);
  std::vector<float> window;
  for (int y = 0; y < rows; ++y) {
    for (int s = 0; s < kSectors; ++s) {
      const int centre = static_cast<int>(std::lround((s + 0.5) * w / kSectors));
      window.clear();
      for (int dx = -half; dx <= half; ++dx) window.push_back(L.at<float>(y, ((centre + dx) % w + w) % w));
      const size_t k = static_cast<size_t>(quantile * (window.size() - 1));
      std::nth_element(window.begin(), window.begin() + k, window.end());
      sector_ref.at<float>(y, s) = window[k];
    }
  }
  for (int y = 1; y < rows; ++y)
    for (int s = 0; s < kSectors; ++s)
      sector_ref.at<float>(y, s) =
          std::max(sector_ref.at<float>(y, s), sector_ref.at<float>(y - 1, s) - static_cast<float>(max_drop_per_row));
  cv::Mat ref(rows, w, CV_32F);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < w; ++x) {
      const double u = (x + 0.5) * kSectors / w - 0.5;
      const int s0 = static_cast<int>(std::floor(u));
      const double t = u - s0;
      const float a = sector_ref.at<float>(y, (s0 + kSectors) % kSectors), b = sector_ref.at<float>(y, (s0 + 1) % kSectors);
      ref.at<float>(y, x) = static_cast<float>((1.0 - t) * a + t * b);
    }
  }
  return ref;
}

// A component with at least this many dark pixels on the ground band stands on the ground
// whatever else it touches: a tree line merged with a wide cloud bank beside it (one
// component after the closing or grabCut) keeps the trees, though the bank's hazy contact
// outnumbers theirs. A cloud bank alone has none (bench/results/sky_segmentation.md).
constexpr long long kGroundedDarkPixels = 8;

// The lat-long wraps: a component touching column 0 and one touching the last column on the
// same row are one object. A flag set on either (per label of `labels`) is set on both.
void SpreadAcrossSeam(const cv::Mat& labels, std::vector<char>* flag) {
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < labels.rows; ++y) {
      const int a = labels.at<int>(y, 0), b = labels.at<int>(y, labels.cols - 1);
      if (a > 0 && b > 0 && (*flag)[a] != (*flag)[b]) {
        (*flag)[a] = (*flag)[b] = 1;
        changed = true;
      }
    }
  }
}

// Keeps the components of `candidates` (8-connected, CV_8U 0/255) that stand on the ground:
// they reach a row at or below `band_top_row`, and at least `min_dark_share` of their pixels
// there (or kGroundedDarkPixels) are darker than the sky's reference by `dark_threshold` (log
// units). Returns the kept mask and counts the dropped pixels.
cv::Mat KeepGroundConnected(const cv::Mat& candidates, int band_top_row, const cv::Mat& dark, double dark_threshold,
                            double min_dark_share, long long* dropped) {
  cv::Mat labels;
  const int n = cv::connectedComponents(candidates, labels, 8, CV_32S);
  std::vector<long long> contact(n, 0), dark_contact(n, 0);
  for (int y = std::max(0, band_top_row); y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const int l = labels.at<int>(y, x);
      ++contact[l];
      dark_contact[l] += dark.at<float>(y, x) > dark_threshold;
    }
  std::vector<char> grounded(n, 0);
  for (int l = 1; l < n; ++l)
    grounded[l] = contact[l] > 0 && (static_cast<double>(dark_contact[l]) >= min_dark_share * contact[l] ||
                                     dark_contact[l] >= kGroundedDarkPixels);
  SpreadAcrossSeam(labels, &grounded);
  cv::Mat kept(candidates.size(), CV_8U, cv::Scalar(0));
  *dropped = 0;
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const int l = labels.at<int>(y, x);
      if (l == 0) continue;
      if (grounded[l]) kept.at<uchar>(y, x) = 255;
      else ++*dropped;
    }
  return kept;
}

// 8-bit BGR picture of the band for grabCut's colour models: log radiance per channel,
// the 1st..99.5th percentile of log luminance mapped to 0..255.
cv::Mat GrabCutImage(const ImageRGB& f, int rows, const cv::Mat& L) {
  std::vector<float> v(L.begin<float>(), L.end<float>());
  std::sort(v.begin(), v.end());
  const float lo = v[static_cast<size_t>(0.01 * (v.size() - 1))], hi = v[static_cast<size_t>(0.995 * (v.size() - 1))];
  const float scale = 255.0f / std::max(1e-3f, hi - lo);
  cv::Mat img(rows, f.width, CV_8UC3);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < f.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const float value = f.at(x, y, c);
        // Invalid channels take the (filled) log luminance.
        const float lv = (std::isfinite(value) && value > 0.0f) ? std::log(value) : L.at<float>(y, x);
        img.at<cv::Vec3b>(y, x)[2 - c] = cv::saturate_cast<uchar>((lv - lo) * scale);
      }
  return img;
}

}  // namespace

bool SkyMaskOptions::IsValid(std::string* why) const {
  if (!InRange(horizon_deg, -10.0, 30.0)) return Fail(why, "horizon_deg", horizon_deg, "[-10, 30] deg");
  if (!(darkness_quantile > 0.0 && darkness_quantile < 1.0))
    return Fail(why, "darkness_quantile", darkness_quantile, "(0, 1)");
  if (!InRange(darkness_window_deg, 5.0, 360.0))
    return Fail(why, "darkness_window_deg", darkness_window_deg, "[5, 360] deg");
  if (!(darkness_threshold > 0.0 && std::isfinite(darkness_threshold)))
    return Fail(why, "darkness_threshold", darkness_threshold, "> 0, natural-log units");
  if (!InRange(texture_sigma_px, 0.5, 8.0)) return Fail(why, "texture_sigma_px", texture_sigma_px, "[0.5, 8] px");
  if (!(texture_threshold > 0.0 && std::isfinite(texture_threshold)))
    return Fail(why, "texture_threshold", texture_threshold, "> 0, natural-log units");
  if (!InRange(textured_darkness, 0.0, 10.0)) return Fail(why, "textured_darkness", textured_darkness, "[0, 10]");
  if (!InRange(ground_band_deg, 0.0, 45.0)) return Fail(why, "ground_band_deg", ground_band_deg, "[0, 45] deg");
  if (!InRange(ground_dark_share, 0.0, 1.0)) return Fail(why, "ground_dark_share", ground_dark_share, "[0, 1]");
  if (!InRange(sun_exclusion_deg, 0.0, 45.0))
    return Fail(why, "sun_exclusion_deg", sun_exclusion_deg, "[0, 45] deg");
  if (!InRange(line_darkness, 0.0, 10.0)) return Fail(why, "line_darkness", line_darkness, "[0, 10] (0: off)");
  if (grabcut_iterations < 1 || grabcut_iterations > 20)
    return Fail(why, "grabcut_iterations", grabcut_iterations, "an integer in [1, 20]");
  if (dilate_px < 0 || dilate_px > 16) return Fail(why, "dilate_px", dilate_px, "an integer in [0, 16]");
  return true;
}

namespace {

// Gradient energy: the local RMS of a log image about its own blur (`sigma_px`), over twice
// that scale.
cv::Mat Texture(const cv::Mat& L, double sigma_px) {
  const cv::Mat residual = L - BlurWrapped(L, sigma_px);
  cv::Mat energy;
  cv::sqrt(BlurWrapped(residual.mul(residual), 2.0 * sigma_px), energy);
  return energy;
}

// The black-hat of a log image: its 3x3 closing minus itself (> 0 on dark features up to two
// pixels wide, by how much darker they are than what surrounds them); wraps in longitude.
cv::Mat BlackHat(const cv::Mat& L) {
  cv::Mat padded, closed;
  cv::copyMakeBorder(L, padded, 0, 0, 1, 1, cv::BORDER_WRAP);
  cv::morphologyEx(padded, closed, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}), {-1, -1}, 1,
                   cv::BORDER_REPLICATE);
  return closed.colRange(1, L.cols + 1) - L;
}

// The log of channel c over the rows above the horizon; where any channel is invalid, the
// (filled) log luminance `L`.
cv::Mat LogChannel(const ImageRGB& f, int c, const cv::Mat& L) {
  cv::Mat out(L.rows, L.cols, CV_32F);
  for (int y = 0; y < L.rows; ++y)
    for (int x = 0; x < L.cols; ++x) {
      out.at<float>(y, x) = ValidPixel(f, x, y) ? std::log(f.at(x, y, c)) : L.at<float>(y, x);
    }
  return out;
}

// The cues over the rows above the horizon: log luminance, gradient energy and darkness
// below the sky's reference (natural-log units).
struct SkyCues {
  cv::Mat L, energy, dark;
};

SkyCues ComputeSkyCues(const ImageRGB& frame, int rows, const SkyMaskOptions& o) {
  const int h = frame.height;
  SkyCues q;
  cv::Mat valid;
  q.L = LogLuminance(frame, rows, &valid);
  q.energy = Texture(q.L, o.texture_sigma_px);
  // Darkness below the sky's reference; 0.15 log units per degree of elevation at most
  // (a CIE overcast sky darkens 0.03 per degree near the horizon, a twilight sky's far side
  // more; buildings are darker by far more than that over their height).
  const double row_deg = 180.0 / (h - 1);
  q.dark = SkyReference(q.L, o.darkness_quantile, o.darkness_window_deg, 0.05 * row_deg) - q.L;
  return q;
}

// The pixels within `exclusion_deg` of the sun (CV_8U 0/255; none without a sun): its glare
// and the ringing of lossy compression round the disc are no evidence of anything.
cv::Mat NearSun(const std::optional<std::array<double, 3>>& sun, int rows, int w, int h, double exclusion_deg) {
  cv::Mat near(rows, w, CV_8U, cv::Scalar(0));
  if (!sun || exclusion_deg <= 0.0) return near;
  const double cos_exclusion = std::cos(exclusion_deg * M_PI / 180.0);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < w; ++x) {
      const auto v = latlong::PixelDirection(x, y, w, h);
      if (v[0] * (*sun)[0] + v[1] * (*sun)[1] + v[2] * (*sun)[2] > cos_exclusion) near.at<uchar>(y, x) = 255;
    }
  return near;
}

// Non-sky candidates (CV_8U 0/255): dark, or textured and somewhat dark; none near the sun.
cv::Mat NonSkyCandidates(const SkyCues& q, const cv::Mat& near_sun, const SkyMaskOptions& o) {
  const int rows = q.L.rows, w = q.L.cols;
  cv::Mat candidates(rows, w, CV_8U, cv::Scalar(0));
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < w; ++x) {
      if (near_sun.at<uchar>(y, x)) continue;
      const float d = q.dark.at<float>(y, x), e = q.energy.at<float>(y, x);
      if (d > o.darkness_threshold || (e > o.texture_threshold && d > o.textured_darkness))
        candidates.at<uchar>(y, x) = 255;
    }
  // Close small gaps (lattice, foliage) before the connectivity test.
  cv::morphologyEx(candidates, candidates, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
  return candidates;
}

// Thin dark lines hanging from the non-sky class (CV_8U 0/255, `non_sky` included): wires
// slung between pylons, a crane's jib and cables. A wire one pixel wide mixes its dark with the
// bright sky's, so it is neither dark enough for the darkness cue nor wide enough for the
// texture cue's ring. The black-hat of ln Y picks out dark features up to two pixels wide;
// one above `line_darkness` is a line where it is
//   - neutral: an opaque occluder covering part of a pixel scales the sky's three channels by
//     one factor, so their black-hats agree (spread under half the luminance's); a cloud's
//     dark fleck has a colour of its own; or
//   - on a smooth sky: the line closed, its surroundings are under the texture cue's
//     threshold (a wire's colour fringes against a hazy glow), where a cloud's flecks are not.
// Lines join the class when they connect to it (8-connected, wrapping) through line pixels
// above half of `line_darkness`: a wire's faint stretch does not cut it off. None near the sun.
cv::Mat WithThinLinesAttached(const ImageRGB& frame, const cv::Mat& L, const cv::Mat& non_sky, const cv::Mat& near_sun,
                              const SkyMaskOptions& o) {
  if (cv::countNonZero(non_sky) == 0) return non_sky.clone();  // nothing for a line to hang from
  const cv::Mat black_hat = BlackHat(L);
  cv::Mat lo = BlackHat(LogChannel(frame, 0, L)), hi = lo.clone();
  for (int c = 1; c < 3; ++c) {
    const cv::Mat bc = BlackHat(LogChannel(frame, c, L));
    cv::min(lo, bc, lo);
    cv::max(hi, bc, hi);
  }
  const cv::Mat neutral = (hi - lo) < 0.5 * black_hat;
  const cv::Mat smooth = Texture(L + black_hat, o.texture_sigma_px) < o.texture_threshold;
  const cv::Mat eligible = (neutral | smooth) & (near_sun == 0);
  const cv::Mat line = (black_hat > o.line_darkness) & eligible;
  const cv::Mat faint = (black_hat > 0.5 * o.line_darkness) & eligible;
  cv::Mat labels;
  const int n = cv::connectedComponents(faint | non_sky, labels, 8, CV_32S);
  std::vector<char> attached(n, 0);
  for (int y = 0; y < L.rows; ++y)
    for (int x = 0; x < L.cols; ++x)
      if (non_sky.at<uchar>(y, x)) attached[labels.at<int>(y, x)] = 1;
  SpreadAcrossSeam(labels, &attached);
  cv::Mat out = non_sky.clone();
  for (int y = 0; y < L.rows; ++y)
    for (int x = 0; x < L.cols; ++x)
      if (line.at<uchar>(y, x) && attached[labels.at<int>(y, x)]) out.at<uchar>(y, x) = 255;
  return out;
}

// grabCut's seed labels: non-sky is its foreground. Definite: ground-connected and twice
// as dark as the threshold. Definite sky: no candidate nearby, not dark, not textured.
// Counts the (probable) foreground and background pixels.
cv::Mat GrabCutSeeds(const SkyCues& q, const cv::Mat& candidates, const cv::Mat& kept, const SkyMaskOptions& o,
                     long long* fg, long long* bg) {
  const int rows = kept.rows, w = kept.cols;
  cv::Mat gc_mask(rows, w, CV_8U);
  cv::Mat near_candidate;
  cv::dilate(candidates, near_candidate, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < w; ++x) {
      const float d = q.dark.at<float>(y, x), e = q.energy.at<float>(y, x);
      uchar label;
      if (kept.at<uchar>(y, x)) label = d > 2.0 * o.darkness_threshold ? cv::GC_FGD : cv::GC_PR_FGD;
      else if (!near_candidate.at<uchar>(y, x) && d < 0.5 * o.darkness_threshold && e < o.texture_threshold)
        label = cv::GC_BGD;
      else label = cv::GC_PR_BGD;
      gc_mask.at<uchar>(y, x) = label;
      *fg += label == cv::GC_FGD || label == cv::GC_PR_FGD;
      *bg += label == cv::GC_BGD || label == cv::GC_PR_BGD;
    }
  return gc_mask;
}

// The mask and its confidence over the rows above the horizon into m.
void WriteSkyMask(const cv::Mat& non_sky, const cv::Mat& gc_mask, const cv::Mat& dark, const SkyMaskOptions& o,
                  SkyMask& m) {
  const int rows = non_sky.rows, w = non_sky.cols;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const bool ns = non_sky.at<uchar>(y, x) != 0;
      m.sky[i] = ns ? 0.0f : 1.0f;
      m.non_sky_above_horizon += ns;
      const uchar g = gc_mask.at<uchar>(y, x);
      if (g == cv::GC_FGD || g == cv::GC_BGD) {
        m.confidence[i] = 1.0f;
      } else {
        // Distance of the darkness cue from its threshold, in thresholds: 0.5 at the threshold.
        const double t = std::abs(dark.at<float>(y, x) - o.darkness_threshold) / o.darkness_threshold;
        m.confidence[i] = static_cast<float>(0.5 + 0.5 * std::min(1.0, t));
      }
    }
}

}  // namespace

SkyMask EstimateSkyMask(const ImageRGB& frame, const std::optional<std::array<double, 3>>& sun,
                        const SkyMaskOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (frame.empty() || frame.width < 8 || frame.height < 4)
    throw Error("sky mask: the frame is " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                " (expected a lat-long of at least 8x4)");
  const int w = frame.width, h = frame.height;
  const double deg = 180.0 / M_PI;
  // Rows above the horizon: [0, rows); rows of the ground band: [band_top, rows).
  int rows = 0, band_top = 0;
  while (rows < h && latlong::Latitude(rows, h) * deg > o.horizon_deg) ++rows;
  while (band_top < rows && latlong::Latitude(band_top, h) * deg > o.horizon_deg + o.ground_band_deg) ++band_top;
  band_top = std::min(band_top, rows - 1);  // at least the lowest row above the horizon (a coarse frame)

  SkyMask m;
  m.width = w;
  m.height = h;
  m.sky.assign(static_cast<size_t>(w) * h, 0.0f);
  m.confidence.assign(static_cast<size_t>(w) * h, 1.0f);
  m.above_horizon = static_cast<long long>(rows) * w;
  if (rows < 2) return m;

  const SkyCues q = ComputeSkyCues(frame, rows, o);
  const cv::Mat near_sun = NearSun(sun, rows, w, h, o.sun_exclusion_deg);
  const cv::Mat candidates = NonSkyCandidates(q, near_sun, o);
  cv::Mat kept =
      KeepGroundConnected(candidates, band_top, q.dark, o.darkness_threshold, o.ground_dark_share, &m.floating_candidates);
  m.ground_connected_candidates = cv::countNonZero(kept);

  cv::Mat non_sky = kept.clone();
  cv::Mat gc_mask(rows, w, CV_8U);
  if (o.grabcut && m.ground_connected_candidates > 0) {
    long long fg = 0, bg = 0;
    gc_mask = GrabCutSeeds(q, candidates, kept, o, &fg, &bg);
    if (fg > 0 && bg > 0) {
      cv::Mat bgd_model, fgd_model;
      // grabCut initialises its colour models by k-means from OpenCV's per-thread RNG: seed
      // it so the same frame gives the same mask whatever ran before in the process.
      cv::theRNG().state = 0x5EED5EEDull;
      cv::grabCut(GrabCutImage(frame, rows, q.L), gc_mask, cv::Rect(), bgd_model, fgd_model, o.grabcut_iterations,
                  cv::GC_INIT_WITH_MASK);
      cv::Mat fg_now = (gc_mask == cv::GC_FGD) | (gc_mask == cv::GC_PR_FGD);
      long long dropped = 0;
      // grabCut's colour model may also take dark floating cloud: the ground rule again.
      non_sky = KeepGroundConnected(fg_now, band_top, q.dark, o.darkness_threshold, o.ground_dark_share, &dropped);
    }
  } else {
    gc_mask.setTo(cv::GC_PR_BGD);
  }
  if (o.line_darkness > 0.0) non_sky = WithThinLinesAttached(frame, q.L, non_sky, near_sun, o);
  if (o.dilate_px > 0)
    cv::dilate(non_sky, non_sky,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * o.dilate_px + 1, 2 * o.dilate_px + 1}));
  WriteSkyMask(non_sky, gc_mask, q.dark, o, m);
  return m;
}

SegmentationScore ScoreNonSky(const SkyMask& mask, const std::vector<float>& ref, int width, int height,
                              double min_elevation_deg) {
  if (mask.width != width || mask.height != height || ref.size() != static_cast<size_t>(width) * height)
    throw Error("sky mask score: the reference mask is " + std::to_string(width) + "x" + std::to_string(height) +
                ", the estimate " + std::to_string(mask.width) + "x" + std::to_string(mask.height));
  SegmentationScore s;
  for (int y = 0; y < height; ++y) {
    if (latlong::Latitude(y, height) * 180.0 / M_PI <= min_elevation_deg) continue;
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      const bool est = mask.sky[i] < 0.5f, truth = ref[i] < 0.5f;
      ++s.evaluated;
      s.true_non_sky += est && truth;
      s.false_non_sky += est && !truth;
      s.missed_non_sky += !est && truth;
    }
  }
  const double tp = static_cast<double>(s.true_non_sky);
  s.precision = tp + s.false_non_sky > 0 ? tp / (tp + s.false_non_sky) : 1.0;
  s.recall = tp + s.missed_non_sky > 0 ? tp / (tp + s.missed_non_sky) : 1.0;
  s.iou = tp + s.false_non_sky + s.missed_non_sky > 0 ? tp / (tp + s.false_non_sky + s.missed_non_sky) : 1.0;
  return s;
}

}  // namespace skycal::capture
