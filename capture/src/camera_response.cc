#include "camera_response.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numeric>

#include <opencv2/core.hpp>
#include <opencv2/photo.hpp>

#include "emor_prior.h"
#include "skycal/core/parallel_chunks.h"
#include "skycal/core/error.h"

namespace skycal::capture::detail {
namespace {

double SrgbToLinear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// Debevec's solver sees only the sampled pixels, so pick them rather than a blind grid: a
// dense grid of candidates, keep those well exposed (in every channel) in at least two
// brackets (a pixel black or clipped in all but one bracket adds an unknown and no
// constraint), then take `samples` of them evenly spread over brightness so the curve is
// constrained from the darkest to the brightest codes (Debevec & Malik 1997, section 2.1).
std::vector<size_t> SelectDebevecSamples(const std::vector<const BracketImage*>& images, const MergeOptions& o,
                                         int* candidates, int* informative) {
  const BracketImage& first = *images.front();
  const int w = first.width, h = first.height;
  const long long want = std::min<long long>(static_cast<long long>(w) * h, 16LL * o.samples);
  const int cols = std::clamp(static_cast<int>(std::lround(std::sqrt(double(want) * w / h))), 1, w);
  const int rows = std::clamp(static_cast<int>(want / cols), 1, h);
  const WeightTable wt = MakeWeights(o, 255);
  const int lo = wt.low_code, hi = wt.high_code;
  struct Candidate {
    size_t index;
    int key;
  };
  std::vector<Candidate> good, all;
  for (int j = 0; j < rows; ++j) {
    const int y = std::min(h - 1, static_cast<int>((j + 0.5) * h / rows));
    for (int i = 0; i < cols; ++i) {
      const int x = std::min(w - 1, static_cast<int>((i + 0.5) * w / cols));
      const size_t idx = first.index(x, y);
      int key = 0, min_good = 1 << 20;
      for (int c = 0; c < 3; ++c) {
        int n_good = 0;
        for (const BracketImage* img : images) {
          const int z = Code8(*img, idx + c);
          key += z;
          n_good += (z > lo && z < hi);
        }
        min_good = std::min(min_good, n_good);
      }
      all.push_back({idx, key});
      if (min_good >= 2) good.push_back({idx, key});
    }
  }
  *candidates = static_cast<int>(all.size());
  *informative = static_cast<int>(good.size());
  std::vector<Candidate>& pool = good.size() >= 2 ? good : all;
  std::stable_sort(pool.begin(), pool.end(), [](const Candidate& a, const Candidate& b) { return a.key < b.key; });
  const size_t n = std::min<size_t>(pool.size(), static_cast<size_t>(o.samples));
  std::vector<size_t> picked(n);
  for (size_t s = 0; s < n; ++s) {
    const size_t at = n == 1 ? 0 : static_cast<size_t>(std::llround(double(s) * (pool.size() - 1) / (n - 1)));
    picked[s] = pool[at].index;
  }
  return picked;
}

std::vector<float> FromMat(const cv::Mat& m) {
  std::vector<float> curve(256 * 3);
  for (int z = 0; z < 256; ++z) {
    const cv::Vec3f v = m.at<cv::Vec3f>(z, 0);
    for (int c = 0; c < 3; ++c) curve[z * 3 + c] = v[c];
  }
  return curve;
}

// Codes of one channel at the picked pixels: codes[p * n + j] for pixel p, bracket j.
std::vector<uint8_t> ChannelCodes(const std::vector<const BracketImage*>& images, const std::vector<size_t>& pixel_index,
                                  int c) {
  const size_t n = images.size();
  std::vector<uint8_t> codes(pixel_index.size() * n);
  for (size_t p = 0; p < pixel_index.size(); ++p)
    for (size_t j = 0; j < n; ++j) codes[p * n + j] = Code8(*images[j], pixel_index[p] + c);
  return codes;
}

// Adds lambda^2 s(z)^2 [g(z-1) - 2 g(z) + g(z+1)]^2 to the normal equations of a 256-code
// log curve. s: the unthresholded weight, floor 1/128 (as OpenCV's triangle ends), so codes
// without data follow the smoothness term: past the data the curve continues log-linearly.
void AddSmoothness(cv::Mat* H, const WeightTable& smooth_w, double lambda) {
  for (int z = 1; z < 255; ++z) {
    const double s = lambda * std::max<double>(smooth_w.w[z], 1.0 / 128.0), s2 = s * s;
    const int idx[3] = {z - 1, z, z + 1};
    const double coef[3] = {1.0, -2.0, 1.0};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) H->at<double>(idx[a], idx[b]) += s2 * coef[a] * coef[b];
  }
}

std::vector<double> SolveNormal(const cv::Mat& H, const cv::Mat& rhs, const char* what) {
  cv::Mat x;
  if (!cv::solve(H, rhs, x, cv::DECOMP_CHOLESKY) && !cv::solve(H, rhs, x, cv::DECOMP_SVD))
    throw Error(std::string(what) + " response: the least-squares system is singular");
  std::vector<double> g(256);
  for (int z = 0; z < 256; ++z) g[z] = x.at<double>(z, 0);
  return g;
}

// Debevec & Malik: minimise sum w(Z_pj)^2 [g(Z_pj) - ln E_p - ln k_j]^2 + smoothness
// (AddSmoothness), g(128) = 0, over well-exposed samples only (w = 0 elsewhere). Each ln E_p
// touches only its own <= n rows, so it is eliminated in closed form (Schur complement)
// and the system is 256 x 256 whatever the sample count (AddSamplesEliminatingLnE); a
// sample without a well-exposed bracket adds nothing.
std::vector<double> SolveDebevec(const std::vector<uint8_t>& codes, size_t n, const std::vector<double>& ln_k,
                                 const WeightTable& data_w, const WeightTable& smooth_w, double lambda) {
  cv::Mat H = cv::Mat::zeros(256, 256, CV_64F), rhs = cv::Mat::zeros(256, 1, CV_64F);
  std::vector<double> a(256);
  for (int z = 0; z < 256; ++z) a[z] = double(data_w.w[z]) * data_w.w[z];
  AddSamplesEliminatingLnE(codes, n, ln_k, a, H.ptr<double>(), rhs.ptr<double>());
  H.at<double>(128, 128) += 1.0;
  AddSmoothness(&H, smooth_w, lambda);
  return SolveNormal(H, rhs, "Debevec");
}

// Debevec's solve, then (MergeOptions::emor_prior), when the brackets' steps leave a part of
// the curve periodic in ln x undetermined (UndeterminedPeriod), that part taken from the EMoR
// curve the samples choose instead of from the smoothness term (emor_prior.h): the result
// fits the samples exactly as Debevec's does. *report: whether the prior was used (and why
// not), its fit, and how far it moved the curve (ln units, over the well-exposed codes).
std::vector<double> SolveDebevecWithPrior(const std::vector<uint8_t>& codes, size_t n, const std::vector<double>& ln_k,
                                          const WeightTable& data_w, const WeightTable& smooth_w, double lambda,
                                          const MergeOptions& o, nlohmann::json* report) {
  const std::vector<double> g = SolveDebevec(codes, n, ln_k, data_w, smooth_w, lambda);
  const double period = UndeterminedPeriod(ln_k);
  std::string why;
  const EmorBasis* basis = o.emor_prior && period > 0.0 ? BundledEmorBasis(&why) : nullptr;
  if (!basis) {
    if (!o.emor_prior) why = "MergeOptions::emor_prior is off";
    if (period == 0.0) why = "the brackets' steps are not multiples of one step: they determine the curve's wiggles";
    *report = {{"used", false}, {"why", why}};
    return g;
  }
  const int lo = data_w.low_code, hi = data_w.high_code;
  const EmorFit fit = FitEmorToSamples(*basis, codes, n, ln_k, lo, hi, g, o.emor_coefficients);
  *report = {{"used", fit.usable}, {"undetermined_period_stops", period / std::log(2.0)}, {"coefficients", fit.c},
             {"rms_code", fit.rms_dn}, {"residuals", fit.residuals}, {"iterations", fit.iterations}};
  if (!fit.usable) {
    (*report)["why"] = fit.why;
    return g;
  }
  const std::vector<double> out = AdoptPeriodicPart(g, fit.g, period, lo, hi, smooth_w.w);
  double mean = 0.0, low = 1e300, high = -1e300;
  for (int z = lo + 1; z < hi; ++z) mean += (out[z] - g[z]) / (hi - lo - 1);
  for (int z = lo + 1; z < hi; ++z) low = std::min(low, out[z] - g[z] - mean), high = std::max(high, out[z] - g[z] - mean);
  (*report)["moved_ln"] = {low, high};
  return out;
}

// Robertson, Borman & Stevenson: alternate E_p = sum w k_j f(Z) / sum w k_j^2 and
// f(m) = mean of k_j E_p over the samples with code m, only well-exposed samples entering
// either step. With brackets at a constant ratio (2 stops each) a wiggle of f periodic in
// ln x with that ratio's period is invisible to this objective (Grossberg & Nayar 2003), so
// the f step is regularised like Debevec's: ln f fits ln(mean) with each code weighted by
// its sample count relative to the average code's (times w^2), plus AddSmoothness; codes
// without samples follow the smoothness term. f(128) = 1.
std::vector<double> SolveRobertson(const std::vector<uint8_t>& codes, size_t n, const std::vector<double>& k,
                                   const WeightTable& wt, const WeightTable& smooth_w, double lambda, int max_iterations,
                                   double threshold, int* iterations) {
  const size_t pixels = codes.size() / n;
  std::vector<double> f(256), E(pixels);
  for (int z = 0; z < 256; ++z) f[z] = std::max(z, 1) / 128.0;  // linear start
  *iterations = 0;
  for (int it = 0; it < max_iterations; ++it) {
    for (size_t p = 0; p < pixels; ++p) {
      double num = 0.0, den = 0.0;
      for (size_t j = 0; j < n; ++j) {
        const int z = codes[p * n + j];
        const double w = wt.w[z];
        num += w * k[j] * f[z];
        den += w * k[j] * k[j];
      }
      E[p] = den > 0.0 ? num / den : -1.0;
    }
    std::vector<double> sum(256, 0.0);
    std::vector<long long> count(256, 0);
    for (size_t p = 0; p < pixels; ++p) {
      if (!(E[p] > 0.0)) continue;
      for (size_t j = 0; j < n; ++j) {
        const int z = codes[p * n + j];
        if (wt.w[z] > 0.0f) sum[z] += k[j] * E[p], ++count[z];
      }
    }
    long long total = 0;
    int used = 0;
    for (int z = 0; z < 256; ++z)
      if (count[z] > 0) total += count[z], ++used;
    if (used < 3) throw Error("Robertson response: fewer than 3 codes are well exposed");
    const double mean_count = double(total) / used;
    cv::Mat H = cv::Mat::zeros(256, 256, CV_64F), rhs = cv::Mat::zeros(256, 1, CV_64F);
    for (int z = 0; z < 256; ++z) {
      if (count[z] == 0) continue;
      const double a = count[z] / mean_count * double(wt.w[z]) * wt.w[z];
      H.at<double>(z, z) += a;
      rhs.at<double>(z, 0) += a * std::log(sum[z] / count[z]);
    }
    AddSmoothness(&H, smooth_w, lambda);
    const std::vector<double> g = SolveNormal(H, rhs, "Robertson");
    double change = 0.0;
    for (int z = 0; z < 256; ++z) {
      const double v = std::exp(g[z] - g[128]);
      if (z > wt.low_code && z < wt.high_code) change += std::fabs(std::log(v) - std::log(f[z]));
      f[z] = v;
    }
    *iterations = it + 1;
    if (change / std::max(1, wt.high_code - wt.low_code - 1) < threshold) break;
  }
  return f;
}

}  // namespace

double ChannelShapeDifference(const std::array<std::vector<double>, 3>& g, int lo, int hi) {
  double worst = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      double mean = 0.0;
      for (int z = lo; z <= hi; ++z) mean += g[a][z] - g[b][z];
      mean /= (hi - lo + 1);
      double ss = 0.0;
      for (int z = lo; z <= hi; ++z) ss += (g[a][z] - g[b][z] - mean) * (g[a][z] - g[b][z] - mean);
      worst = std::max(worst, std::sqrt(ss / (hi - lo + 1)));
    }
  return worst;
}

void AddSamplesEliminatingLnE(const std::vector<uint8_t>& codes, size_t n, const std::vector<double>& ln_k,
                              const std::vector<double>& a, double* H, double* rhs) {
  const size_t samples = codes.size() / n;
  std::vector<int> zs;
  std::vector<double> hs;
  for (size_t p = 0; p < samples; ++p) {
    // Rows sqrt(a) (g(z_j) - ln E - ln k_j); ln E touches only these, so it is eliminated:
    // H -= h h^T / D, rhs -= h r_E / D (h: the g-ln E block, D: the ln E diagonal).
    double D = 0.0, rE = 0.0;
    zs.clear();
    hs.clear();
    for (size_t j = 0; j < n; ++j) {
      const int z = codes[p * n + j];
      const double w = a[z];
      if (!(w > 0.0)) continue;
      H[z * 256 + z] += w;
      rhs[z] += w * ln_k[j];
      D += w;
      rE -= w * ln_k[j];
      const auto it = std::find(zs.begin(), zs.end(), z);
      if (it == zs.end()) {
        zs.push_back(z);
        hs.push_back(-w);
      } else {
        hs[it - zs.begin()] -= w;
      }
    }
    if (zs.empty()) continue;
    for (size_t u = 0; u < zs.size(); ++u) {
      rhs[zs[u]] -= hs[u] * rE / D;
      for (size_t v = 0; v < zs.size(); ++v) H[zs[u] * 256 + zs[v]] -= hs[u] * hs[v] / D;
    }
  }
}

WeightTable MakeWeights(const MergeOptions& o, int max_code, bool thresholded) {
  WeightTable t;
  t.w.resize(static_cast<size_t>(max_code) + 1);
  t.low_code = static_cast<int>(std::floor(o.low_threshold * max_code));
  t.high_code = static_cast<int>(std::ceil(o.high_threshold * max_code));
  for (int z = 0; z <= max_code; ++z) {
    const double v = double(z) / max_code;
    double w = o.weight == WeightFunction::kHat
                   ? 1.0 - std::fabs(2.0 * v - 1.0)
                   : std::exp(-(v - 0.5) * (v - 0.5) / (2.0 * o.gaussian_sigma * o.gaussian_sigma));
    if (thresholded) {
      if (z <= t.low_code || z >= t.high_code)
        w = 0.0;
      else
        w = std::max(w, 1e-6);  // well exposed means weight > 0, whatever the function
    }
    t.w[z] = static_cast<float>(std::max(w, 0.0));
  }
  return t;
}

std::vector<float> AnalyticResponse(ResponseModel model, int levels) {
  std::vector<float> curve(static_cast<size_t>(levels) * 3);
  for (int z = 0; z < levels; ++z) {
    const double v = double(z) / (levels - 1);
    const float lin = static_cast<float>(model == ResponseModel::kSrgb ? SrgbToLinear(v) : v);
    for (int c = 0; c < 3; ++c) curve[static_cast<size_t>(z) * 3 + c] = lin;
  }
  return curve;
}

namespace {

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// kWeighted / kAuto: the noise-weighted log response per channel; kAuto hands over to
// Debevec's solve when the channels' curves share one shape.
std::vector<float> RecoverWeighted(const std::vector<const BracketImage*>& images,
                                   const std::vector<double>& relative_exposure, const MergeOptions& o,
                                   nlohmann::json* report, std::chrono::steady_clock::time_point t0) {
  const size_t n = images.size();
  std::vector<float> curve;
  std::vector<double> ln_k(n);
  for (size_t j = 0; j < n; ++j) ln_k[j] = std::log(relative_exposure[j]);
  curve.assign(256 * 3, 0.0f);
  std::vector<nlohmann::json> per_channel(3);
  std::array<std::vector<double>, 3> g;
  ParallelChunks(3, ResolveThreads(o.threads), [&](int c0, int c1, int) {
    for (int c = c0; c < c1; ++c) {
      g[c] = RecoverWeightedLogResponse(images, ln_k, c, o, &per_channel[c]);
      for (int z = 0; z < 256; ++z) curve[z * 3 + c] = static_cast<float>(std::exp(g[c][z] - g[c][255]));
    }
  });
  nlohmann::json cal = {{"method", "weighted"}, {"solver", "skycal (noise-weighted log response)"}, {"channels", per_channel}};
  if (o.response == ResponseModel::kAuto) {
    const double difference = ChannelShapeDifference(g, o.weighted_low_code, o.weighted_high_code);
    nlohmann::json choice = {{"channel_shape_difference", difference}, {"tolerance", o.auto_shape_tolerance}};
    if (difference <= o.auto_shape_tolerance) {
      // One shape in every channel: Debevec's solve, one curve for the three channels
      // (CalibrateSharedDebevec: the per-channel solves' own extrapolations of the top codes
      // unbalance the channels), bench/results/capture-response/capture-response.md.
      MergeOptions debevec = o;
      debevec.response = ResponseModel::kDebevec;
      nlohmann::json sub;
      std::vector<float> d = RecoverResponse(images, relative_exposure, debevec, &sub, /*shared_curve=*/true);
      nlohmann::json out = sub["calibration"];
      choice["chose"] = "debevec";
      choice["reason"] = "the channels' recovered curves have one shape";
      out["auto"] = choice;
      if (report) (*report)["calibration"] = out;
      return d;
    }
    choice["chose"] = "weighted";
    choice["reason"] = "the channels' recovered curves differ in shape";
    cal["auto"] = choice;
  }
  cal["decreasing_steps"] = NormaliseResponse(&curve, 256);
  cal["time_ms"] = MsSince(t0);
  if (report) (*report)["calibration"] = cal;
  return curve;
}

// Pixels: Debevec a few picked ones, Robertson a stride-subsampled grid. The choice's
// report goes into cal.
std::vector<size_t> CalibrationPixels(const std::vector<const BracketImage*>& images, const MergeOptions& o,
                                      nlohmann::json* cal) {
  const BracketImage& first = *images.front();
  std::vector<size_t> pixel_index;
  if (o.response == ResponseModel::kDebevec) {
    int candidates = 0, informative = 0;
    pixel_index = SelectDebevecSamples(images, o, &candidates, &informative);
    *cal = {{"method", "debevec"}, {"samples", pixel_index.size()}, {"candidates", candidates},
            {"informative_candidates", informative}, {"lambda", o.lambda}};
  } else if (o.response == ResponseModel::kRobertson) {
    const long long total = static_cast<long long>(first.width) * first.height;
    const int stride = o.calibration_max_pixels > 0 && total > o.calibration_max_pixels
                           ? static_cast<int>(std::ceil(std::sqrt(double(total) / o.calibration_max_pixels)))
                           : 1;
    for (int y = 0; y < first.height; y += stride)
      for (int x = 0; x < first.width; x += stride) pixel_index.push_back(first.index(x, y));
    *cal = {{"method", "robertson"}, {"pixels", pixel_index.size()}, {"stride", stride},
            {"max_iterations", o.robertson_max_iterations}, {"threshold", o.robertson_threshold}};
  } else {
    throw Error("internal: RecoverResponse called for an analytic response model");
  }
  return pixel_index;
}

// OpenCV's Debevec or Robertson calibration over the picked pixels.
std::vector<float> CalibrateWithOpenCv(const std::vector<const BracketImage*>& images,
                                       const std::vector<size_t>& pixel_index,
                                       const std::vector<double>& relative_exposure, const MergeOptions& o) {
  // The picked pixels as a 1 x n image per bracket (Debevec: OpenCV's grid over a 1 x n
  // image takes every pixel, so it sees exactly our selection).
  std::vector<cv::Mat> mats;
  for (const BracketImage* img : images) {
    cv::Mat m(1, static_cast<int>(pixel_index.size()), CV_8UC3);
    for (size_t s = 0; s < pixel_index.size(); ++s)
      for (int c = 0; c < 3; ++c) m.at<cv::Vec3b>(0, static_cast<int>(s))[c] = Code8(*img, pixel_index[s] + c);
    mats.push_back(m);
  }
  const std::vector<float> times(relative_exposure.begin(), relative_exposure.end());
  cv::Mat out;
  if (o.response == ResponseModel::kDebevec)
    cv::createCalibrateDebevec(static_cast<int>(pixel_index.size()), static_cast<float>(o.lambda), false)->process(mats, out, times);
  else
    cv::createCalibrateRobertson(o.robertson_max_iterations, static_cast<float>(o.robertson_threshold))->process(mats, out, times);
  if (out.rows != 256 || out.type() != CV_32FC3) throw Error("OpenCV response calibration returned an unexpected curve");
  return FromMat(out);
}

// One Debevec curve for the three channels: every picked pixel's three channels enter one
// solve as three samples (3x the equations), and the curve is copied to each channel.
//
// Why, for a curve the channels share (kAuto's one-shape case): Debevec's solve per channel
// leaves each channel's scale to its own extrapolation of ln f past the well-exposed codes
// (the top code is full scale, the gauge), and that extrapolation differs between channels
// by the noise and by how each channel's samples fall on the curve's toe and shoulder: a
// colour imbalance that no global scale removes, largest where the shoulder is strong (the
// top codes then span a stop or more, so the extrapolation is long). Constant-ratio
// brackets leave a component of ln f periodic in ln x (period: the ratio) undetermined
// (Grossberg & Nayar, "What can be known about the radiometric response from images?",
// ECCV 2002); the smoothness prior picks it, and the only equations that pin it on a steep
// S-curve 2 EV apart tie a mid-tone code to a toe or shoulder code of the next bracket,
// which the hat weight (squared) gives ~1% of a mid-tone equation's say. Three channels in
// one solve give the prior three times those equations and one extrapolation, not three.
// lambda is scaled by sqrt(3) so that the smoothness keeps the say relative to the data
// that MergeOptions::lambda was chosen for on one channel's samples.
std::vector<float> CalibrateSharedDebevec(const std::vector<const BracketImage*>& images,
                                          const std::vector<size_t>& pixel_index, const std::vector<double>& ln_k,
                                          const WeightTable& data_w, const WeightTable& smooth_w, const MergeOptions& o,
                                          nlohmann::json* prior_report) {
  std::vector<uint8_t> codes;
  for (int c = 0; c < 3; ++c) {
    const std::vector<uint8_t> channel = ChannelCodes(images, pixel_index, c);
    codes.insert(codes.end(), channel.begin(), channel.end());
  }
  const std::vector<double> g =
      SolveDebevecWithPrior(codes, images.size(), ln_k, data_w, smooth_w, o.lambda * std::sqrt(3.0), o, prior_report);
  std::vector<float> curve(256 * 3);
  for (int z = 0; z < 256; ++z)
    for (int c = 0; c < 3; ++c) curve[z * 3 + c] = static_cast<float>(std::exp(g[z]));
  return curve;
}

// skycal's Debevec or Robertson solve over the picked pixels' well-exposed samples (Debevec
// with `shared`: one curve for the three channels, CalibrateSharedDebevec); Robertson's
// iteration counts go into cal.
std::vector<float> CalibrateWellExposed(const std::vector<const BracketImage*>& images,
                                        const std::vector<size_t>& pixel_index,
                                        const std::vector<double>& relative_exposure, const MergeOptions& o,
                                        bool shared, nlohmann::json* cal) {
  const size_t n = images.size();
  std::vector<float> curve;
  const WeightTable data_w = MakeWeights(o, 255, true), smooth_w = MakeWeights(o, 255, false);
  std::vector<double> ln_k(n);
  for (size_t j = 0; j < n; ++j) ln_k[j] = std::log(relative_exposure[j]);
  if (shared && o.response == ResponseModel::kDebevec) {
    (*cal)["channels"] = "one curve for the three channels";
    return CalibrateSharedDebevec(images, pixel_index, ln_k, data_w, smooth_w, o, &(*cal)["emor_prior"]);
  }
  curve.assign(256 * 3, 0.0f);
  std::vector<int> iterations(3, 0);
  std::vector<nlohmann::json> prior(3);
  // One channel per worker (the three solves are independent).
  ParallelChunks(3, ResolveThreads(o.threads), [&](int c0, int c1, int) {
    for (int c = c0; c < c1; ++c) {
      const std::vector<uint8_t> codes = ChannelCodes(images, pixel_index, c);
      std::vector<double> lin(256);
      if (o.response == ResponseModel::kDebevec) {
        const std::vector<double> g = SolveDebevecWithPrior(codes, n, ln_k, data_w, smooth_w, o.lambda, o, &prior[c]);
        for (int z = 0; z < 256; ++z) lin[z] = std::exp(g[z]);
      } else {
        lin = SolveRobertson(codes, n, relative_exposure, data_w, smooth_w, o.lambda, o.robertson_max_iterations,
                             o.robertson_threshold, &iterations[c]);
      }
      for (int z = 0; z < 256; ++z) curve[z * 3 + c] = static_cast<float>(lin[z]);
    }
  });
  if (o.response == ResponseModel::kRobertson) (*cal)["iterations"] = iterations;
  if (o.response == ResponseModel::kDebevec) (*cal)["emor_prior"] = prior;
  return curve;
}

}  // namespace

std::vector<float> RecoverResponse(const std::vector<const BracketImage*>& images,
                                   const std::vector<double>& relative_exposure, const MergeOptions& o,
                                   nlohmann::json* report, bool shared_curve) {
  const auto t0 = std::chrono::steady_clock::now();
  if (o.response == ResponseModel::kWeighted || o.response == ResponseModel::kAuto)
    return RecoverWeighted(images, relative_exposure, o, report, t0);
  nlohmann::json cal;
  const std::vector<size_t> pixel_index = CalibrationPixels(images, o, &cal);
  cal["solver"] = o.opencv_calibration ? "opencv" : "skycal (well-exposed samples only)";
  std::vector<float> curve = o.opencv_calibration
                                 ? CalibrateWithOpenCv(images, pixel_index, relative_exposure, o)
                                 : CalibrateWellExposed(images, pixel_index, relative_exposure, o, shared_curve, &cal);
  int non_finite = 0;
  for (float v : curve) non_finite += !std::isfinite(v);
  cal["non_finite_codes_filled"] = non_finite;  // OpenCV's Robertson divides by a zero count for unseen codes
  cal["decreasing_steps"] = NormaliseResponse(&curve, 256);
  cal["time_ms"] = MsSince(t0);
  if (report) (*report)["calibration"] = cal;
  return curve;
}

int NormaliseResponse(std::vector<float>* curve, int levels) {
  int decreasing = 0;
  std::vector<float>& v = *curve;
  for (int c = 0; c < 3; ++c) {
    auto at = [&](int z) -> float& { return v[static_cast<size_t>(z) * 3 + c]; };
    int last = -1;  // last finite code
    for (int z = 0; z < levels; ++z) {
      if (!std::isfinite(at(z))) continue;
      if (last < 0) {
        for (int k = 0; k < z; ++k) at(k) = at(z);
      } else {
        for (int k = last + 1; k < z; ++k) at(k) = at(last) + (at(z) - at(last)) * float(k - last) / float(z - last);
      }
      last = z;
    }
    if (last < 0) throw Error("camera response: no finite value in channel " + std::to_string(c));
    for (int k = last + 1; k < levels; ++k) at(k) = at(last);
    float top = std::max(at(levels - 1), 0.0f);
    if (!(top > 0.0f))
      for (int z = 0; z < levels; ++z) top = std::max(top, at(z));
    if (!(top > 0.0f)) throw Error("camera response: channel " + std::to_string(c) + " is zero everywhere");
    for (int z = 0; z < levels; ++z) {
      at(z) = std::max(at(z), 0.0f) / top;
      if (z > 0 && at(z) < at(z - 1)) ++decreasing;
    }
  }
  return decreasing;
}

std::vector<float> ExpandResponse(const std::vector<float>& curve256) {
  std::vector<float> out(65536 * 3);
  for (int z = 0; z < 65536; ++z) {
    const double u = z / 257.0;
    const int i = std::min(254, static_cast<int>(u));
    const float f = static_cast<float>(u - i);
    for (int c = 0; c < 3; ++c)
      out[static_cast<size_t>(z) * 3 + c] = curve256[i * 3 + c] * (1.0f - f) + curve256[(i + 1) * 3 + c] * f;
  }
  return out;
}

}  // namespace skycal::capture::detail
