#include "skycal/capture/hdr_merge.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <sstream>
#include <utility>

#include "camera_response.h"
#include "skycal/core/parallel_chunks.h"
#include "skycal/core/error.h"

namespace skycal::capture {
namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

std::string Num(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

std::string Label(const Bracket& b, size_t i) {
  return b.path.empty() ? "bracket " + std::to_string(i) : b.path;
}

// Per worker tallies, summed after the merge.
struct Tally {
  long long well = 0, over = 0, under = 0, gap = 0;
  std::vector<long long> good_samples, clipped_samples;  // per bracket (sorted order), channel samples
};

}  // namespace

const char* ResponseModelName(ResponseModel m) {
  switch (m) {
    case ResponseModel::kAuto: return "auto";
    case ResponseModel::kWeighted: return "weighted";
    case ResponseModel::kDebevec: return "debevec";
    case ResponseModel::kRobertson: return "robertson";
    case ResponseModel::kLinear: return "linear";
    case ResponseModel::kSrgb: return "srgb";
  }
  return "?";
}

ResponseModel ParseResponseModel(const std::string& name, const std::string& what) {
  for (ResponseModel m : {ResponseModel::kAuto, ResponseModel::kWeighted, ResponseModel::kDebevec, ResponseModel::kRobertson, ResponseModel::kLinear, ResponseModel::kSrgb})
    if (name == ResponseModelName(m)) return m;
  throw Error(what + ": unknown response model '" + name + "' (expected auto, weighted, debevec, robertson, linear or srgb)");
}

bool MergeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    *why = m;
    return false;
  };
  if (samples < 2) return fail("samples: need >= 2 pixel locations for the response calibration, got " + std::to_string(samples));
  if (!(lambda > 0.0) || !std::isfinite(lambda)) return fail("lambda: need a finite smoothness weight > 0, got " + Num(lambda));
  if (emor_coefficients < 1 || emor_coefficients > 6)
    return fail("emor_coefficients: need 1..6 (the bundled EMoR basis has 6 curves), got " + std::to_string(emor_coefficients));
  if (weighted_samples < 2) return fail("weighted_samples: need >= 2, got " + std::to_string(weighted_samples));
  if (!(weighted_lambda > 0.0) || !std::isfinite(weighted_lambda))
    return fail("weighted_lambda: need a finite smoothness weight > 0, got " + Num(weighted_lambda));
  if (weighted_iterations < 0 || weighted_iterations > 20) return fail("weighted_iterations: need 0..20");
  if (!(weighted_low_code >= 1 && weighted_low_code + 8 <= weighted_high_code && weighted_high_code <= 254))
    return fail("weighted_low_code/weighted_high_code: need 1 <= low, low + 8 <= high <= 254 (8-bit codes)");
  if (!(auto_shape_tolerance >= 0.0) || !std::isfinite(auto_shape_tolerance))
    return fail("auto_shape_tolerance: need a finite value >= 0 (ln f units), got " + Num(auto_shape_tolerance));
  if (robertson_max_iterations < 1) return fail("robertson_max_iterations: need >= 1");
  if (!(robertson_threshold > 0.0)) return fail("robertson_threshold: need > 0");
  if (calibration_max_pixels < 0) return fail("calibration_max_pixels: need >= 0 (0 = all)");
  if (!(gaussian_sigma > 0.0) || !std::isfinite(gaussian_sigma)) return fail("gaussian_sigma: need a finite value > 0");
  if (!(low_threshold >= 0.0 && low_threshold < high_threshold && high_threshold <= 1.0))
    return fail("low_threshold/high_threshold: need 0 <= low < high <= 1, got " + Num(low_threshold) + ", " + Num(high_threshold));
  if (threads < 0) return fail("threads: need >= 0 (0 = hardware concurrency)");
  if (!response_curve.empty()) {
    const size_t levels = response_curve.size() / 3;
    if (response_curve.size() % 3 != 0 || (levels != 256 && levels != 65536))
      return fail("response_curve: need 256 * 3 or 65536 * 3 values (R G B per code), got " + std::to_string(response_curve.size()));
    for (float v : response_curve)
      if (!std::isfinite(v) || v < 0.0f) return fail("response_curve: values must be finite and >= 0");
  }
  return true;
}

nlohmann::json MergeOptionsToJson(const MergeOptions& o) {
  return {{"response", o.response_curve.empty() ? ResponseModelName(o.response) : "fixed_curve"},
          {"fixed_curve_levels", o.response_curve.size() / 3},
          {"samples", o.samples},
          {"lambda", o.lambda},
          {"emor_prior", o.emor_prior},
          {"emor_coefficients", o.emor_coefficients},
          {"weighted_samples", o.weighted_samples},
          {"weighted_lambda", o.weighted_lambda},
          {"weighted_iterations", o.weighted_iterations},
          {"weighted_codes", {o.weighted_low_code, o.weighted_high_code}},
          {"auto_shape_tolerance", o.auto_shape_tolerance},
          {"robertson_max_iterations", o.robertson_max_iterations},
          {"robertson_threshold", o.robertson_threshold},
          {"calibration_max_pixels", o.calibration_max_pixels},
          {"weight", o.weight == WeightFunction::kHat ? "hat" : "gaussian"},
          {"gaussian_sigma", o.gaussian_sigma},
          {"low_threshold", o.low_threshold},
          {"high_threshold", o.high_threshold},
          {"exposure_weighting", o.exposure_weighting},
          {"opencv_calibration", o.opencv_calibration},
          {"threads", o.threads}};
}

namespace {

// --- validation: images ------------------------------------------------------------------
void ValidateImages(const std::vector<Bracket>& brackets) {
  const size_t n = brackets.size();
  const BracketImage& first = brackets[0].image;
  for (size_t i = 0; i < n; ++i) {
    const BracketImage& im = brackets[i].image;
    const std::string name = Label(brackets[i], i);
    if (im.empty()) throw Error(name + ": empty image");
    if (im.bits != 8 && im.bits != 16) throw Error(name + ": bits must be 8 or 16, got " + std::to_string(im.bits));
    if (im.rgb.size() != static_cast<size_t>(im.width) * im.height * 3)
      throw Error(name + ": pixel buffer holds " + std::to_string(im.rgb.size()) + " values, expected width*height*3");
    if (im.width != first.width || im.height != first.height)
      throw Error(name + ": size " + std::to_string(im.width) + "x" + std::to_string(im.height) + " differs from " +
                  Label(brackets[0], 0) + " (" + std::to_string(first.width) + "x" + std::to_string(first.height) +
                  "); brackets must be the same size");
    if (im.bits != first.bits)
      throw Error(name + ": " + std::to_string(im.bits) + "-bit, but " + Label(brackets[0], 0) + " is " +
                  std::to_string(first.bits) + "-bit; brackets must share a bit depth");
    if (!im.saturated.empty() && im.saturated.size() != static_cast<size_t>(im.width) * im.height)
      throw Error(name + ": saturation mask holds " + std::to_string(im.saturated.size()) +
                  " values, expected width*height (or none)");
    if (im.linear != first.linear)
      throw Error(name + (im.linear ? " is" : " is not") + " camera RAW (linear) but " + Label(brackets[0], 0) +
                  (first.linear ? " is" : " is not") + "; one set of brackets is all RAW or none");
  }
}

// Which of f-number and ISO enter the exposure factor k (each: known for every bracket).
struct ExposureFields {
  bool use_n = false, use_iso = false;
};

// --- validation: exposures ---------------------------------------------------------------
ExposureFields ValidateExposures(const std::vector<Bracket>& brackets) {
  const size_t n = brackets.size();
  int with_n = 0, with_iso = 0;
  for (size_t i = 0; i < n; ++i) {
    const Bracket& b = brackets[i];
    const std::string name = Label(b, i);
    if (std::isnan(b.exposure_time_s))
      throw Error(name + ": exposure time missing (no explicit time and no EXIF ExposureTime)");
    if (!std::isfinite(b.exposure_time_s) || b.exposure_time_s <= 0.0)
      throw Error(name + ": exposure time must be finite and > 0 s, got " + Num(b.exposure_time_s));
    if (!std::isnan(b.f_number) && !(std::isfinite(b.f_number) && b.f_number > 0.0))
      throw Error(name + ": f-number must be finite and > 0 (or unknown), got " + Num(b.f_number));
    if (!std::isnan(b.iso) && !(std::isfinite(b.iso) && b.iso > 0.0))
      throw Error(name + ": ISO must be finite and > 0 (or unknown), got " + Num(b.iso));
    with_n += !std::isnan(b.f_number);
    with_iso += !std::isnan(b.iso);
  }
  auto all_or_none = [&](int count, double Bracket::*field, const char* what) {
    if (count == 0 || count == static_cast<int>(n)) return;
    for (size_t i = 0; i < n; ++i)
      if (std::isnan(brackets[i].*field))
        throw Error(Label(brackets[i], i) + ": " + what + " unknown while other brackets have one; the exposure " +
                    "scale needs it for every bracket or for none");
  };
  all_or_none(with_n, &Bracket::f_number, "f-number");
  all_or_none(with_iso, &Bracket::iso, "ISO");
  return {with_n == static_cast<int>(n), with_iso == static_cast<int>(n)};
}

// Exposure factor k per bracket into r (factors, scale, aperture/ISO flag); returns the
// bracket indices sorted by k. Throws when two brackets share an exposure.
std::vector<size_t> ExposureOrder(const std::vector<Bracket>& brackets, ExposureFields fields, MergeResult& r) {
  const size_t n = brackets.size();
  const bool use_n = fields.use_n, use_iso = fields.use_iso;
  r.exposure_factors.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Bracket& b = brackets[i];
    double k = b.exposure_time_s;
    if (use_iso) k *= b.iso / 100.0;
    if (use_n) k /= b.f_number * b.f_number;
    r.exposure_factors[i] = k;
  }
  r.exposure_uses_aperture_iso = use_n || use_iso;
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return r.exposure_factors[a] < r.exposure_factors[b]; });
  for (size_t s = 0; s + 1 < n; ++s) {
    const size_t a = order[s], b = order[s + 1];
    if (r.exposure_factors[b] < r.exposure_factors[a] * (1.0 + 1e-3))
      throw Error(Label(brackets[b], b) + ": same exposure as " + Label(brackets[a], a) + " (t = " +
                  Num(brackets[b].exposure_time_s) + " s vs " + Num(brackets[a].exposure_time_s) +
                  " s, after f-number and ISO); each bracket needs a distinct exposure time");
  }
  r.exposure_scale = 1.0 / r.exposure_factors[order[(n - 1) / 2]];
  return order;
}

// --- response curve ----------------------------------------------------------------------
// A failed recovery's context: the options field that chose it and each bracket (shortest
// exposure first) with its time and the share of its channel samples inside the codes the
// recovery reads (merge options weighted_low_code..weighted_high_code, on the 8-bit scale),
// so an all-black or all-clipped file is named.
std::string RecoveryContext(const std::vector<Bracket>& brackets, const std::vector<size_t>& order,
                            const MergeOptions& o) {
  const int shift = brackets[0].image.bits == 16 ? 8 : 0;
  std::ostringstream s;
  s << "response recovery (merge options field 'response' = " << ResponseModelName(o.response) << ") from "
    << order.size() << " brackets, shortest exposure first, each with its share of channel samples in codes "
    << o.weighted_low_code << ".." << o.weighted_high_code << " (8-bit scale):";
  for (size_t i : order) {
    const BracketImage& im = brackets[i].image;
    size_t inside = 0;
    for (uint16_t v : im.rgb) {
      const int z = v >> shift;
      inside += z >= o.weighted_low_code && z <= o.weighted_high_code;
    }
    const double share = im.rgb.empty() ? 0.0 : 100.0 * static_cast<double>(inside) / static_cast<double>(im.rgb.size());
    s << " '" << Label(brackets[i], i) << "' (t = " << Num(brackets[i].exposure_time_s) << " s, " << Num(share) << "%)";
    if (i != order.back()) s << ",";
  }
  return s.str();
}

// Fills r.response_curve and r.response_levels (fixed, analytic or recovered from the
// brackets sorted by exposure); returns the curve's source name.
std::string ChooseResponse(const std::vector<Bracket>& brackets, const std::vector<size_t>& order,
                           const std::vector<const BracketImage*>& sorted_images, const std::vector<double>& relative,
                           const MergeOptions& options, MergeResult& r, nlohmann::json* response_report) {
  const BracketImage& first = brackets[0].image;
  const int levels = first.max_code() + 1;
  if (first.linear) {
    // Camera RAW: codes are proportional to light by construction (raw_decode.h), so the
    // response is the identity and nothing is recovered; a model or curve asked for explicitly
    // is refused rather than ignored.
    if (!options.response_curve.empty() || (options.response != ResponseModel::kAuto && options.response != ResponseModel::kLinear))
      throw Error(std::string("merge options: response = ") +
                  (options.response_curve.empty() ? ResponseModelName(options.response) : "fixed_curve") + ": " +
                  Label(brackets[0], 0) + " and the other brackets are camera RAW, linear by construction " +
                  "(identity response); use auto or linear");
    r.response_curve = detail::AnalyticResponse(ResponseModel::kLinear, levels);
    r.response_levels = levels;
    (*response_report)["method"] = "identity: camera RAW input is linear (black subtracted, white level = top code); no response recovery";
    return "raw_linear";
  }
  if (!options.response_curve.empty()) {
    r.response_curve = options.response_curve;
    const int given = static_cast<int>(r.response_curve.size() / 3);
    if (given == 65536 && first.bits == 8)
      throw Error("merge options: response_curve has 65536 levels but the brackets are 8-bit (" + Label(brackets[0], 0) + ")");
    r.response_levels = given;
    return "fixed_curve";
  }
  if (options.response == ResponseModel::kLinear || options.response == ResponseModel::kSrgb) {
    r.response_curve = detail::AnalyticResponse(options.response, levels);
    r.response_levels = levels;
    return ResponseModelName(options.response);
  }
  try {
    r.response_curve = detail::RecoverResponse(sorted_images, relative, options, response_report);
  } catch (const Error& e) {
    throw Error(RecoveryContext(brackets, order, options) + ": " + e.what());
  }
  r.response_levels = 256;
  return ResponseModelName(options.response);
}

// Lookup tables over the brackets' codes (linear value per channel, weight, class) and per
// bracket (sorted by exposure) 1 / k, the exposure weight and the pixel plane.
struct MergeTables {
  std::vector<float> lut;
  std::vector<float> weight;
  int low_code = 0, high_code = 0, max_code = 0;
  std::vector<float> inv_k, k_weight;
  std::vector<const uint16_t*> planes;
  std::vector<const uint8_t*> saturated;  // per bracket: the RAW saturation mask, or nullptr
};

MergeTables MakeTables(const MergeResult& r, const std::vector<size_t>& order, const std::vector<double>& relative,
                       const std::vector<const BracketImage*>& sorted_images, const MergeOptions& options, int levels,
                       int max_code) {
  const size_t n = order.size();
  MergeTables tb;
  tb.lut = r.response_levels == levels ? r.response_curve : detail::ExpandResponse(r.response_curve);
  tb.max_code = max_code;
  detail::WeightTable weights = detail::MakeWeights(options, max_code);
  tb.weight = std::move(weights.w);
  tb.low_code = weights.low_code, tb.high_code = weights.high_code;
  tb.inv_k.resize(n), tb.k_weight.resize(n), tb.planes.resize(n), tb.saturated.resize(n);
  for (size_t s = 0; s < n; ++s) {
    tb.inv_k[s] = static_cast<float>(1.0 / r.exposure_factors[order[s]]);
    tb.k_weight[s] = options.exposure_weighting ? static_cast<float>(relative[s]) : 1.0f;
    tb.planes[s] = sorted_images[s]->rgb.data();
    tb.saturated[s] = sorted_images[s]->saturated.empty() ? nullptr : sorted_images[s]->saturated.data();
  }
  return tb;
}

// One channel sample i = p * 3 + c across the brackets: the weighted mean of the
// well-exposed ones, or a bound when none is (flags says which); counts into t.
float MergeSample(const MergeTables& tb, size_t n, size_t i, int c, Tally& t, uint8_t& flags) {
  const std::vector<float>& lut = tb.lut;
  const std::vector<float>& weight = tb.weight;
  const std::vector<float>& inv_k = tb.inv_k;
  const std::vector<float>& k_weight = tb.k_weight;
  const std::vector<const uint16_t*>& planes = tb.planes;
  const int max_code = tb.max_code, low_code = tb.low_code, high_code = tb.high_code;
  // A sample of a saturated RAW pixel counts as clipped whatever its code (weight 0).
  auto clipped = [&](size_t s, int z) { return z >= high_code || (tb.saturated[s] && tb.saturated[s][i / 3]); };
  float sum = 0.0f, sum_w = 0.0f;
  for (size_t s = 0; s < n; ++s) {
    const int z = std::min<int>(planes[s][i], max_code);
    const float wz = tb.saturated[s] && tb.saturated[s][i / 3] ? 0.0f : weight[z];
    if (wz > 0.0f) {
      const float ws = wz * k_weight[s];
      sum += ws * lut[static_cast<size_t>(z) * 3 + c] * inv_k[s];
      sum_w += ws;
      ++t.good_samples[s];
    } else if (clipped(s, z)) {
      ++t.clipped_samples[s];
    }
  }
  float e;
  if (sum_w > 0.0f) {
    e = sum / sum_w;
  } else {
    const int z_short = std::min<int>(planes[0][i], max_code), z_long = std::min<int>(planes[n - 1][i], max_code);
    if (clipped(0, z_short)) {  // clipped even in the shortest: its value is a lower bound
      e = lut[static_cast<size_t>(z_short) * 3 + c] * inv_k[0];
      flags |= kPixelOverExposed;
    } else if (z_long <= low_code) {  // black even in the longest: its value is an upper bound
      e = lut[static_cast<size_t>(z_long) * 3 + c] * inv_k[n - 1];
      flags |= kPixelUnderExposed;
    } else {
      // Black in some brackets, clipped in the others, well exposed in none: midway
      // between the longest black bracket's bound and the shortest clipped one's.
      size_t dark = 0, bright = n - 1;
      for (size_t s = 0; s < n; ++s)
        if (std::min<int>(planes[s][i], max_code) <= low_code) dark = s;
      for (size_t s = n; s-- > 0;)
        if (clipped(s, std::min<int>(planes[s][i], max_code))) bright = s;
      const int zd = std::min<int>(planes[dark][i], max_code), zb = std::min<int>(planes[bright][i], max_code);
      e = 0.5f * (lut[static_cast<size_t>(zd) * 3 + c] * inv_k[dark] + lut[static_cast<size_t>(zb) * 3 + c] * inv_k[bright]);
      flags |= kPixelGap;
    }
  }
  return e;
}

// --- per-pixel merge ---------------------------------------------------------------------
// Radiance, flags and well-measured mask into r; per-worker tallies, summed into r's
// counts. Returns the per-bracket (sorted order) good and clipped channel-sample counts.
std::pair<std::vector<long long>, std::vector<long long>> MergePixels(const MergeTables& tb, size_t n, int w, int h,
                                                                      int threads, MergeResult& r) {
  r.radiance = ImageRGB(w, h);
  r.well_measured.assign(static_cast<size_t>(w) * h, 0.0f);
  r.flags.assign(static_cast<size_t>(w) * h, 0);
  std::vector<Tally> tallies(threads);  // fewer rows than threads: the unused ones stay zero
  for (auto& t : tallies) t.good_samples.assign(n, 0), t.clipped_samples.assign(n, 0);
  ParallelChunks(h, threads, [&](int y0, int y1, int worker) {
    // Counters live on this worker's stack and are stored once at the end: adjacent Tally
    // objects share cache lines, and per-pixel writes to them would serialise the workers.
    Tally t;
    t.good_samples.assign(n, 0);
    t.clipped_samples.assign(n, 0);
    for (size_t p = static_cast<size_t>(y0) * w; p < static_cast<size_t>(y1) * w; ++p) {
      uint8_t flags = 0;
      for (int c = 0; c < 3; ++c) {
        const size_t i = p * 3 + c;
        const float e = MergeSample(tb, n, i, c, t, flags);
        r.radiance.pixels[i] = std::isfinite(e) && e > 0.0f ? e : 0.0f;
      }
      r.flags[p] = flags;
      if (flags == 0) {
        r.well_measured[p] = 1.0f;
        ++t.well;
      }
      t.over += (flags & kPixelOverExposed) != 0;
      t.under += (flags & kPixelUnderExposed) != 0;
      t.gap += (flags & kPixelGap) != 0;
    }
    tallies[worker] = std::move(t);
  });

  std::vector<long long> good(n, 0), clipped(n, 0);
  for (const Tally& t : tallies) {
    r.well_measured_pixels += t.well;
    r.over_exposed += t.over;
    r.under_exposed += t.under;
    r.gap += t.gap;
    for (size_t s = 0; s < n; ++s) good[s] += t.good_samples[s], clipped[s] += t.clipped_samples[s];
  }
  return {std::move(good), std::move(clipped)};
}

// --- report: per bracket -----------------------------------------------------------------
nlohmann::json BracketsReport(const std::vector<Bracket>& brackets, const std::vector<size_t>& order,
                              ExposureFields fields, const MergeResult& r, const std::vector<long long>& good,
                              const std::vector<long long>& clipped, long long total) {
  const size_t n = brackets.size();
  const bool use_n = fields.use_n, use_iso = fields.use_iso;
  nlohmann::json bj = nlohmann::json::array();
  std::vector<size_t> rank(n);
  for (size_t s = 0; s < n; ++s) rank[order[s]] = s;
  for (size_t i = 0; i < n; ++i) {
    const Bracket& b = brackets[i];
    auto opt = [](double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); };
    const double ev100 = std::log2((use_n ? b.f_number * b.f_number : 1.0) / b.exposure_time_s) -
                         (use_iso ? std::log2(b.iso / 100.0) : 0.0);
    const long long saturated = std::count(b.image.saturated.begin(), b.image.saturated.end(), uint8_t{1});
    bj.push_back({{"path", b.path},
                  {"exposure_time_s", b.exposure_time_s},
                  {"f_number", opt(b.f_number)},
                  {"iso", opt(b.iso)},
                  {"exposure_factor", r.exposure_factors[i]},
                  {"ev100", ev100},
                  {"well_exposed_fraction", double(good[rank[i]]) / (3.0 * total)},
                  {"clipped_fraction", double(clipped[rank[i]]) / (3.0 * total)},
                  {"raw_saturated_fraction", b.image.saturated.empty() ? nlohmann::json() : nlohmann::json(double(saturated) / total)}});
  }
  return bj;
}

}  // namespace

MergeResult MergeBrackets(const std::vector<Bracket>& brackets, const MergeOptions& options) {
  const auto t_start = Clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw Error("merge options: " + why);
  const size_t n = brackets.size();
  if (n < 2)
    throw Error("HDR merge needs at least two exposures, got " + std::to_string(n) +
                (n == 1 ? " (" + Label(brackets[0], 0) + ")" : std::string()));
  ValidateImages(brackets);
  const BracketImage& first = brackets[0].image;
  const ExposureFields fields = ValidateExposures(brackets);
  MergeResult r;
  const std::vector<size_t> order = ExposureOrder(brackets, fields, r);
  const double k_max = r.exposure_factors[order.back()];
  const auto t_validated = Clock::now();

  nlohmann::json response_report;
  std::vector<const BracketImage*> sorted_images(n);
  std::vector<double> relative(n);
  for (size_t s = 0; s < n; ++s) {
    sorted_images[s] = &brackets[order[s]].image;
    relative[s] = r.exposure_factors[order[s]] / k_max;
  }
  const int levels = first.max_code() + 1;
  const std::string source = ChooseResponse(brackets, order, sorted_images, relative, options, r, &response_report);
  // A recovered curve: whether these brackets determine it (a warning, not a quiet error).
  std::vector<std::string> warnings;
  if (response_report.contains("calibration"))
    response_report["determinacy"] = detail::ResponseDeterminacy(sorted_images, options, &warnings);
  const auto t_response = Clock::now();

  MergeTables tb = MakeTables(r, order, relative, sorted_images, options, levels, first.max_code());
  const auto t_tables = Clock::now();

  const int w = first.width, h = first.height;
  const int threads = ResolveThreads(options.threads);
  const auto [good, clipped] = MergePixels(tb, n, w, h, threads, r);
  const auto t_merged = Clock::now();
  const long long total = static_cast<long long>(w) * h;
  r.not_well_measured = total - r.well_measured_pixels;

  // --- report ------------------------------------------------------------------------------
  response_report["source"] = source;
  response_report["levels"] = r.response_levels;
  response_report["normalisation"] = "top code = 1 per channel";
  const size_t mid = static_cast<size_t>(r.response_levels / 2) * 3;
  response_report["mid_code_linear"] = {r.response_curve[mid], r.response_curve[mid + 1], r.response_curve[mid + 2]};
  r.report = {
      {"width", w},
      {"height", h},
      {"bits", first.bits},
      {"brackets", BracketsReport(brackets, order, fields, r, good, clipped, total)},
      {"unit", r.exposure_uses_aperture_iso
                   ? "linear sensor value (full scale 1) / (t[s] * ISO/100 / N^2)"
                   : "linear sensor value (full scale 1) / t[s] (no f-number/ISO known)"},
      {"exposure_scale", r.exposure_scale},
      {"exposure_uses_f_number", fields.use_n},
      {"exposure_uses_iso", fields.use_iso},
      {"pixels",
       {{"total", total},
        {"well_measured", r.well_measured_pixels},
        {"not_well_measured", r.not_well_measured},
        {"over_exposed", r.over_exposed},
        {"under_exposed", r.under_exposed},
        {"gap", r.gap}}},
      {"codes", {{"black_at_or_below", tb.low_code}, {"clipped_at_or_above", tb.high_code}, {"max", tb.max_code}}},
      {"response", response_report},
      {"options", MergeOptionsToJson(options)},
      {"threads", threads},
      {"timings_ms",
       {{"validate", Ms(t_start, t_validated)},
        {"response", Ms(t_validated, t_response)},
        {"tables", Ms(t_response, t_tables)},
        {"merge", Ms(t_tables, t_merged)},
        {"total", Ms(t_start, Clock::now())}}}};
  r.report["warnings"] = warnings;
  return r;
}

}  // namespace skycal::capture
