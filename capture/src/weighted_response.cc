// Noise-weighted camera-response recovery (ResponseModel::kWeighted): Debevec & Malik's
// least squares on the log response, g(z) = ln f(z), with three changes that matter on
// 8-bit brackets (measured in bench/results/capture-response/capture-response.md):
//  - thousands of samples, not 70: each channel keeps the pixels with >= 2 codes inside
//    the fit range, spread evenly over brightness (rank of the code sum, which rises with
//    radiance whatever the curve), so every code is constrained by many equations; the
//    per-sample unknowns ln E are eliminated in closed form, so the system stays 256 x 256;
//  - inverse-variance weights: a code z carries noise sigma_z (DN), i.e. sigma_z g'(z) in
//    ln f, so its equation is weighted 1 / g'(z)^2 (iterated: the slope of the previous
//    solution; the first pass assumes a gamma 2.2 curve). The hat weight of the original
//    gives the toe, where g' is largest, far too much say;
//  - the fit range stops short of both ends (codes 3..252 by default): a sensor clipped at
//    full scale reads 254 as often as 255 under 0.6 DN of noise, and black reads 1 or 2,
//    and these samples' equations would be wrong by the whole overexposure.
// The smoothness term lambda^2 sum (g(z-1) - 2 g(z) + g(z+1))^2 is in the same units (the
// data term is a chi-square with 1 DN of noise), so lambda does not depend on the sample
// count or exposure spacing; it resolves the ambiguity that brackets at one constant ratio
// leave (a wiggle of g periodic in ln f with that ratio's period fits them exactly;
// Grossberg & Nayar 2003) and continues the curve log-linearly past the fit range.
#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "camera_response.h"
#include "skycal/core/error.h"

namespace skycal::capture::detail {
namespace {

// Pixels of channel c with >= 2 codes in [lo, hi], at most `samples`, evenly over the rank
// of their code sum. Candidates: a grid of at most 65536 pixels.
std::vector<size_t> SelectSamples(const std::vector<const BracketImage*>& images, int c, int lo, int hi, int samples,
                                  int* candidates) {
  const BracketImage& first = *images.front();
  const long long total = static_cast<long long>(first.width) * first.height;
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(total) / 65536.0))));
  std::vector<std::pair<int, size_t>> pool;  // (code sum, index)
  *candidates = 0;
  for (int y = stride / 2; y < first.height; y += stride)
    for (int x = stride / 2; x < first.width; x += stride) {
      const size_t idx = first.index(x, y) + c;
      int sum = 0, good = 0;
      for (const BracketImage* img : images) {
        const int z = Code8(*img, idx);
        sum += z;
        good += z >= lo && z <= hi;
      }
      ++*candidates;
      if (good >= 2) pool.push_back({sum, idx});
    }
  std::stable_sort(pool.begin(), pool.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  const size_t n = std::min(pool.size(), static_cast<size_t>(samples));
  std::vector<size_t> picked(n);
  for (size_t s = 0; s < n; ++s)
    picked[s] = pool[n == 1 ? 0 : static_cast<size_t>(std::llround(double(s) * (pool.size() - 1) / (n - 1)))].second;
  return picked;
}

// One weighted solve: data weight a[z] per code (0 outside the fit range), smoothness
// lambda^2 on every second difference, g(pin) = 0 (the gauge, fixed again later).
Eigen::VectorXd Solve(const std::vector<uint8_t>& codes, size_t n, const std::vector<double>& ln_k,
                      const std::vector<double>& a, double lambda, int pin) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(256, 256);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(256);
  AddSamplesEliminatingLnE(codes, n, ln_k, a, H.data(), rhs.data());
  const double l2 = lambda * lambda;
  const double coef[3] = {1.0, -2.0, 1.0};
  for (int z = 0; z + 3 <= 256; ++z)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) H(z + i, z + j) += l2 * coef[i] * coef[j];
  H(pin, pin) += 1.0;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
  Eigen::VectorXd g = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !g.allFinite()) throw Error("weighted response: the least-squares system is singular");
  return g;
}

}  // namespace

std::vector<double> RecoverWeightedLogResponse(const std::vector<const BracketImage*>& images,
                                               const std::vector<double>& ln_k, int c, const MergeOptions& o,
                                               nlohmann::json* report) {
  const size_t n = images.size();
  const int lo = o.weighted_low_code, hi = o.weighted_high_code;
  int candidates = 0;
  const std::vector<size_t> picked = SelectSamples(images, c, lo, hi, o.weighted_samples, &candidates);
  if (picked.size() < 2)
    throw Error("weighted response: channel " + std::to_string(c) + " has fewer than 2 pixels with two codes in " +
                std::to_string(lo) + ".." + std::to_string(hi) + " (brackets too far apart, or all black / clipped)");
  std::vector<uint8_t> codes(picked.size() * n);
  for (size_t p = 0; p < picked.size(); ++p)
    for (size_t j = 0; j < n; ++j) codes[p * n + j] = Code8(*images[j], picked[p]);
  std::vector<double> a(256, 0.0);
  for (int z = lo; z <= hi; ++z) a[z] = (z / 2.2) * (z / 2.2);  // first pass: g = 2.2 ln(z / 255), g' = 2.2 / z
  const int pin = std::clamp(128, lo, hi);
  Eigen::VectorXd g;
  for (int it = 0; it <= o.weighted_iterations; ++it) {
    g = Solve(codes, n, ln_k, a, o.weighted_lambda, pin);
    if (it == o.weighted_iterations) break;
    for (int z = lo; z <= hi; ++z) {
      // Slope per code (central difference), floored at 1/50 of its typical value so that a
      // flat stretch of the previous solution cannot take all the weight.
      const double slope = 0.5 * (g(std::min(z + 1, 255)) - g(std::max(z - 1, 0)));
      const double typical = std::max(1e-6, (g(hi) - g(lo)) / double(hi - lo));
      const double s = std::max(slope, typical / 50.0);
      a[z] = 1.0 / (s * s);
    }
  }
  if (report)
    *report = {{"samples", picked.size()}, {"candidates", candidates}, {"fit_codes", {lo, hi}},
               {"iterations", o.weighted_iterations}, {"lambda", o.weighted_lambda}};
  return std::vector<double>(g.data(), g.data() + 256);
}

}  // namespace skycal::capture::detail
