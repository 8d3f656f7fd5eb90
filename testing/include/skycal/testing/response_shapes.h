// Camera responses the merge code has never seen, for response-recovery tests and the
// bench (`skycal bench --suite capture-response`, bench/src/capture_response_suite.cc): brackets of a real sky made through them with photon,
// read and DN noise and clipping (synthetic_brackets.h's camera, another tone curve), the
// merge through the true curve (the "known-response merge") as the floor to compare against.
//
// Every curve maps linear sensor value x in [0, 1] (after white balance: every channel
// clips at 1) to a normalised code v in [0, 1], increasing, 0 -> 0 and 1 -> 1: the top code
// is full scale in every channel, the convention a recovered curve's gauge relies on
// (hdr_merge.h, MergeResult::response_curve).
#pragma once
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "skycal/capture/emor.h"
#include "skycal/testing/synthetic_brackets.h"

namespace skycal::synthetic {

using ToneCurve = std::function<double(double)>;

struct ResponseShape {
  std::string name;
  std::array<ToneCurve, 3> encode;  // R, G, B: x in [0, 1] -> v in [0, 1]
};

// S-curve on a log axis: a logistic in log2 x (slope a per stop, centre c stops), rescaled so
// that x = 1 gives 1 (x -> 0 gives 0).
inline ToneCurve LogisticInStops(double a, double c) {
  return [a, c](double x) {
    if (x <= 0.0) return 0.0;
    auto s = [&](double u) { return 1.0 / (1.0 + std::exp(-a * (std::log2(u) - c))); };
    return s(x) / s(1.0);
  };
}

// A film-like curve with a toe and a shoulder: John Hable's filmic operator (the Uncharted 2
// curve, GDC 2010: a rational function with shoulder strength, linear strength and angle,
// toe strength, numerator and denominator), white point w, then a display gamma.
inline ToneCurve FilmToeShoulder(double w, double gamma) {
  auto h = [](double u) {
    const double A = 0.15, B = 0.50, C = 0.10, D = 0.20, E = 0.02, F = 0.30;
    return (u * (A * u + C * B) + D * E) / (u * (A * u + B) + D * F) - E / F;
  };
  return [h, w, gamma](double x) { return std::pow(std::max(0.0, h(x * w) / h(w)), 1.0 / gamma); };
}

// A power law with a smooth video-style knee: tanh(b x^(1/g)) / tanh(b).
inline ToneCurve GammaKnee(double g, double b) {
  return [g, b](double x) { return std::tanh(b * std::pow(std::max(x, 0.0), 1.0 / g)) / std::tanh(b); };
}

// A display gamma followed by the contrast S y^a / (y^a + (1-y)^a).
inline ToneCurve GammaContrast(double g, double a) {
  return [g, a](double x) {
    const double y = std::pow(std::clamp(x, 0.0, 1.0), 1.0 / g), p = std::pow(y, a), q = std::pow(1.0 - y, a);
    return p / (p + q);
  };
}

inline std::vector<ResponseShape> UnseenResponseShapes() {
  return {
      {"log-S (logistic in stops)", {LogisticInStops(0.85, -2.3), LogisticInStops(0.85, -2.3), LogisticInStops(0.85, -2.3)}},
      {"film toe+shoulder (Hable)", {FilmToeShoulder(11.2, 2.2), FilmToeShoulder(11.2, 2.2), FilmToeShoulder(11.2, 2.2)}},
      {"gamma 1.8 + knee", {GammaKnee(1.8, 1.3), GammaKnee(1.8, 1.3), GammaKnee(1.8, 1.3)}},
      {"per-channel (3 shapes)", {FilmToeShoulder(6.0, 2.0), LogisticInStops(1.0, -2.0), GammaKnee(2.4, 1.6)}},
  };
}

// A curve whose slope is zero at white (gamma 2.6, then the contrast S with a = 1.5, the
// family of synthetic_brackets.h's filmic curve): codes 252..255 span 13% of the sensor
// range, so the top code's value (the gauge) is an extrapolation; the same in every channel,
// that error is one global scale and divides out (bench/results/capture-response/capture-response.md).
inline ResponseShape FlatShoulderShape() {
  return {"flat shoulder (gamma 2.6 + contrast S)", {GammaContrast(2.6, 1.5), GammaContrast(2.6, 1.5), GammaContrast(2.6, 1.5)}};
}

// A second held-out family, for a method that uses the EMoR itself as its prior (the
// Debevec solve's MergeOptions::emor_prior): the transfer curves camera makers and standards
// publish, none of them from the DoRF database or the EMoR. Each curve V(L) of scene-linear
// L (black at V(0), the curve's own offset removed) is scaled so that its top code is L_max,
// where V reaches 1 (or L = 1 for the display OETFs): v(x) = (V(x L_max) - V(0)) / (V(L_max) - V(0)).
// Formulas from the published documents: IEC 61966-2-1 (sRGB), ITU-R BT.709-6 and BT.2100-2
// (HLG), Sony's "Technical Summary for S-Gamut3.Cine/S-Log3", ARRI's "ALEXA Log C Curve"
// (LogC3, EI 800), Panasonic's "V-Log/V-Gamut Reference Manual", Canon's Canon Log
// white paper, Fujifilm's "F-Log Data Sheet", and the Academy's ACEScct (S-2016-001).
struct PublishedCurve {
  std::string name;
  std::function<double(double)> V;  // scene-linear L >= 0 -> code value
  double l_max;                      // L at the top code
};

inline std::vector<PublishedCurve> PublishedCameraCurveFormulas() {
  const auto log10 = [](double v) { return std::log10(v); };
  return {
      {"sRGB (IEC 61966-2-1)", [](double L) { return L <= 0.0031308 ? 12.92 * L : 1.055 * std::pow(L, 1.0 / 2.4) - 0.055; }, 1.0},
      {"BT.709 OETF", [](double L) { return L < 0.018 ? 4.5 * L : 1.099 * std::pow(L, 0.45) - 0.099; }, 1.0},
      {"BT.2100 HLG OETF",
       [](double L) {
         const double a = 0.17883277, b = 1.0 - 4.0 * a, c = 0.5 - a * std::log(4.0 * a);
         return L <= 1.0 / 12.0 ? std::sqrt(3.0 * L) : a * std::log(12.0 * L - b) + c;
       },
       1.0},
      {"Sony S-Log3",
       [log10](double L) {
         return L >= 0.01125 ? (420.0 + log10((L + 0.01) / 0.19) * 261.5) / 1023.0
                             : (L * (171.2102946929 - 95.0) / 0.01125 + 95.0) / 1023.0;
       },
       0.19 * std::pow(10.0, (1023.0 - 420.0) / 261.5) - 0.01},
      {"ARRI LogC3 (EI 800)",
       [log10](double L) { return L > 0.010591 ? 0.247190 * log10(5.555556 * L + 0.052272) + 0.385537 : 5.367655 * L + 0.092809; },
       (std::pow(10.0, (1.0 - 0.385537) / 0.247190) - 0.052272) / 5.555556},
      {"Panasonic V-Log",
       [log10](double L) { return L < 0.01 ? 5.6 * L + 0.125 : 0.241514 * log10(L + 0.00873) + 0.598206; },
       std::pow(10.0, (1.0 - 0.598206) / 0.241514) - 0.00873},
      {"Canon Log", [log10](double L) { return 0.529136 * log10(10.1596 * L + 1.0) + 0.0730597; },
       (std::pow(10.0, (1.0 - 0.0730597) / 0.529136) - 1.0) / 10.1596},
      {"Fujifilm F-Log",
       [log10](double L) { return L >= 0.00089 ? 0.344676 * log10(0.555556 * L + 0.009468) + 0.790453 : 8.735631 * L + 0.092864; },
       (std::pow(10.0, (1.0 - 0.790453) / 0.344676) - 0.009468) / 0.555556},
      {"ACEScct",
       [](double L) { return L <= 0.0078125 ? 10.5402377416545 * L + 0.0729055341958355 : (std::log2(L) + 9.72) / 17.52; },
       std::exp2(17.52 - 9.72)},
  };
}

// The published curves as shapes (the same curve in the three channels).
inline std::vector<ResponseShape> PublishedCameraShapes() {
  std::vector<ResponseShape> out;
  for (const PublishedCurve& c : PublishedCameraCurveFormulas()) {
    const double v0 = c.V(0.0), v1 = c.V(c.l_max);
    const ToneCurve t = [c, v0, v1](double x) { return (c.V(std::clamp(x, 0.0, 1.0) * c.l_max) - v0) / (v1 - v0); };
    out.push_back({c.name, {t, t, t}});
  }
  return out;
}

// The EMoR family: curves of Grossberg & Nayar's Empirical Model of Response
// (skycal/capture/emor.h, the same basis file). The merge's defaults were set without them;
// since the Debevec solve takes the EMoR as its prior (MergeOptions::emor_prior) they no
// longer measure `auto` from outside, and PublishedCameraShapes above is the held-out family
// (bench/results/capture-response/capture-response.md, their own sections).
using capture::EmorBasis;

// The curve through the samples, linear between them.
inline ToneCurve SampledCurve(std::vector<double> samples) {
  auto f = std::make_shared<const std::vector<double>>(std::move(samples));
  return [f](double x) {
    const double u = std::clamp(x, 0.0, 1.0) * double(f->size() - 1);
    const size_t i = std::min(f->size() - 2, static_cast<size_t>(u));
    return (*f)[i] + ((*f)[i + 1] - (*f)[i]) * (u - double(i));
  };
}

// `count` curves of the family, one per bracket set, the same in the three channels (a
// camera's tone curve applied after white balance). Coefficients: c1 ~ U(-4, 5), c2..c6
// ~ N(0, {1.0, 0.4, 0.25, 0.12, 0.08}). No per-coefficient spread of the DoRF curves is
// published in the sources at hand; these ranges are the ones the basis gives standard curves
// (c1: linear +6.5, gamma 1/1.8 +1.5, sRGB -0.1, gamma 1/3 -2.2, a logistic in stops with
// a long shoulder -5.3; |c2| <= 3.3, |c3| <= 0.9, |c4| <= 0.6, |c5|, |c6| <= 0.2).
// A draw whose curve is not strictly increasing over the 1024 samples is drawn again
// (`rejected` counts them). `coefficients` (optional) receives each curve's c.
inline std::vector<ResponseShape> EmorHeldOutShapes(const EmorBasis& b, int count, unsigned seed,
                                                    std::vector<std::array<double, 6>>* coefficients = nullptr,
                                                    int* rejected = nullptr) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> c1(-4.0, 5.0);
  const double sigma[5] = {1.0, 0.4, 0.25, 0.12, 0.08};
  std::vector<ResponseShape> out;
  if (rejected) *rejected = 0;
  while (static_cast<int>(out.size()) < count) {
    std::array<double, 6> c{};
    c[0] = c1(rng);
    for (int i = 1; i < 6; ++i) c[i] = std::normal_distribution<double>(0.0, sigma[i - 1])(rng);
    const std::vector<double> f = capture::EmorCurve(b, c);
    bool increasing = true;
    for (size_t k = 1; k < f.size() && increasing; ++k) increasing = f[k] > f[k - 1] && f[k] <= 1.0;
    if (!increasing) {
      if (rejected) ++*rejected;
      continue;
    }
    char name[96];
    std::snprintf(name, sizeof name, "EMoR %d (c1 %+.2f, c2 %+.2f, c3 %+.2f)", static_cast<int>(out.size()) + 1, c[0], c[1], c[2]);
    const ToneCurve t = SampledCurve(f);
    out.push_back({name, {t, t, t}});
    if (coefficients) coefficients->push_back(c);
  }
  return out;
}

struct ShapeBracketSpec {
  int brackets = 5;
  double ev_step = 2.0;         // stops between consecutive brackets
  // Each bracket's exposure in stops from 1/60 s, ascending (brackets' count and spacing
  // when not empty, overriding `brackets` and `ev_step`): unequal steps.
  std::vector<double> stops;
  double dn_noise = 0.6;        // Gaussian noise in 8-bit code units, after the tone curve
  double full_well_e = 10000.0; // photon noise as synthetic_brackets.h's camera
  double read_noise_e = 3.0;
  unsigned seed = 1;
};

// The inverse of an increasing curve on [0, 1] by bisection.
inline double InvertCurve(const ToneCurve& f, double v) {
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < v ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// 8-bit brackets of `scene` through `shape`: times 1/60 s * 2^(ev (i - (n-1)/2)), f/8 ISO 100,
// the gain putting the scene's median luminance at 0.18 of full scale in the middle bracket.
// truth_response is the true curve at each code (what a known-response merge uses).
inline SyntheticBrackets MakeShapeBrackets(const ImageRGB& scene, const ResponseShape& shape, const ShapeBracketSpec& spec) {
  BracketSpec base;
  base.exposure_times_s.clear();
  for (int i = 0; i < spec.brackets && spec.stops.empty(); ++i)
    base.exposure_times_s.push_back(std::exp2(spec.ev_step * (i - 0.5 * (spec.brackets - 1))) / 60.0);
  for (double stop : spec.stops) base.exposure_times_s.push_back(std::exp2(stop) / 60.0);
  base.noise = false;
  base.curve = CameraCurve::kLinear;
  SyntheticBrackets out = MakeSyntheticBrackets(scene, base);  // truth, gain, exposures; codes redone below
  const int n = static_cast<int>(base.exposure_times_s.size());
  std::vector<double> k(n);
  for (int i = 0; i < n; ++i) k[i] = base.exposure_times_s[i] * (base.iso / 100.0) / (base.f_number * base.f_number);
  std::vector<std::thread> pool;
  for (int i = 0; i < n; ++i) {
    pool.emplace_back([&, i] {
      capture::Bracket& b = out.brackets[i];
      std::mt19937 rng(spec.seed * 7919u + static_cast<unsigned>(i));
      std::normal_distribution<double> gauss(0.0, 1.0);
      for (size_t s = 0; s < scene.pixels.size(); ++s) {
        double x = out.gain * scene.pixels[s] * k[i];
        const double e = std::min(x, 2.0) * spec.full_well_e;
        x = (e + std::sqrt(e) * gauss(rng) + spec.read_noise_e * gauss(rng)) / spec.full_well_e;
        const double v = shape.encode[s % 3](std::clamp(x, 0.0, 1.0)) * 255.0 + spec.dn_noise * gauss(rng);
        b.image.rgb[s] = static_cast<uint16_t>(std::clamp<long>(std::lround(v), 0, 255));
      }
    });
  }
  for (auto& t : pool) t.join();
  for (int z = 0; z <= 255; ++z)
    for (int c = 0; c < 3; ++c) out.truth_response[static_cast<size_t>(z) * 3 + c] = static_cast<float>(InvertCurve(shape.encode[c], z / 255.0));
  // Truth mask: every channel's noise-free code well exposed (2%..98%) in at least one bracket.
  out.truth_well_pixels = 0;
  const size_t pixels = static_cast<size_t>(scene.width) * scene.height;
  for (size_t p = 0; p < pixels; ++p) {
    bool all = true;
    for (int c = 0; c < 3 && all; ++c) {
      bool any = false;
      for (int i = 0; i < n && !any; ++i) {
        const long z = std::lround(shape.encode[c](std::min(1.0, out.gain * scene.pixels[3 * p + c] * k[i])) * 255.0);
        any = z > 5 && z < 250;
      }
      all = any;
    }
    out.truth_well[p] = all;
    out.truth_well_pixels += all;
  }
  return out;
}

// Median and p90 relative error of a merge over the truth mask after one global scale (the
// median ratio of all channels together: a recovered curve's overall scale is a gauge, but
// the channels' balance is not, given the top-code convention above).
struct ShapeMergeError {
  double median = 0.0, p90 = 0.0, scale = 1.0;
  std::array<double, 3> channel{1.0, 1.0, 1.0};  // median ratio per channel / scale: the balance error
  // The same after one scale per channel (each channel's median ratio): the error left once
  // the white balance is fixed, as a colour chart fixes it (capture/color_chart.h). A
  // channel's radiance scale is itself a gauge the brackets cannot fix when the channels'
  // curves differ (scaling E_c and the curve's argument together leaves every code as it is).
  double median_balanced = 0.0, p90_balanced = 0.0;
};
inline ShapeMergeError EvaluateShapeMerge(const ImageRGB& merged, const SyntheticBrackets& s) {
  std::vector<double> ratio;
  const size_t pixels = s.truth_well.size();
  for (size_t p = 0; p < pixels; ++p)
    if (s.truth_well[p])
      for (int c = 0; c < 3; ++c) ratio.push_back(merged.pixels[3 * p + c] / s.truth.pixels[3 * p + c]);
  ShapeMergeError e;
  e.scale = Quantile(ratio, 0.5);
  std::vector<double> rel;
  rel.reserve(ratio.size());
  for (double r : ratio) rel.push_back(std::fabs(r / e.scale - 1.0));
  for (int c = 0; c < 3; ++c) {
    std::vector<double> rc;
    for (size_t i = c; i < ratio.size(); i += 3) rc.push_back(ratio[i] / e.scale);
    e.channel[c] = Quantile(rc, 0.5);
  }
  e.median = Quantile(rel, 0.5);
  e.p90 = Quantile(rel, 0.9);
  std::vector<double> balanced;
  balanced.reserve(ratio.size());
  for (size_t i = 0; i < ratio.size(); ++i) balanced.push_back(std::fabs(ratio[i] / (e.scale * e.channel[i % 3]) - 1.0));
  e.median_balanced = Quantile(balanced, 0.5);
  e.p90_balanced = Quantile(balanced, 0.9);
  return e;
}

}  // namespace skycal::synthetic
