#include "emor_prior.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>

#include <ceres/ceres.h>

#include "skycal/core/data_dir.h"

namespace skycal::capture::detail {
namespace {

double Scalar(double v) { return v; }
template <typename J, int N>
double Scalar(const ceres::Jet<J, N>& v) {
  return v.a;
}

// One well-exposed sample: code z of a pixel with log radiance ln E in a bracket of log
// exposure ln k; residual z - 255 f(E k) in codes. f: the basis' table, linear between its
// samples and past E = 1 along its last segment (a well-exposed code predicted beyond the
// clip keeps a gradient).
struct CodeResidual {
  const EmorBasis* basis;
  double code, ln_k;
  template <typename T>
  bool operator()(const T* c, const T* ln_e, T* r) const {
    const T u = exp(ln_e[0] + ln_k) * double(kEmorSamples - 1);
    const int i = std::clamp(static_cast<int>(std::floor(Scalar(u))), 0, kEmorSamples - 2);
    T lo = T(basis->f0[i]), hi = T(basis->f0[i + 1]);
    for (int m = 0; m < 6; ++m) lo += c[m] * basis->h[m][i], hi += c[m] * basis->h[m][i + 1];
    r[0] = T(code) - 255.0 * (lo + (hi - lo) * (u - double(i)));
    return true;
  }
};

// ln f^-1(z / 255) per code from an increasing curve; code 0 (E = 0) continues codes 1-2.
std::vector<double> InverseLog(const std::vector<double>& f) {
  std::vector<double> g(256);
  int k = 0;
  for (int z = 1; z < 256; ++z) {
    const double v = z / 255.0;
    while (k < kEmorSamples - 2 && f[k + 1] < v) ++k;
    const double step = f[k + 1] - f[k];
    const double t = step > 0.0 ? std::clamp((v - f[k]) / step, 0.0, 1.0) : 0.0;
    g[z] = std::log(std::max((k + t) / (kEmorSamples - 1), 1e-9));
  }
  g[0] = 2.0 * g[1] - g[2];
  return g;
}

}  // namespace

const EmorBasis* BundledEmorBasis(std::string* why) {
  static std::once_flag once;
  static std::unique_ptr<EmorBasis> basis;
  static std::string error;
  std::call_once(once, [] {
    try {
      basis = std::make_unique<EmorBasis>(ReadEmorBasis(DataPath("datasets/response/emor_basis.csv")));
    } catch (const std::exception& e) {
      error = e.what();
    }
  });
  if (!basis && why) *why = error;
  return basis.get();
}

EmorFit FitEmorToSamples(const EmorBasis& basis, const std::vector<uint8_t>& codes, size_t n,
                         const std::vector<double>& ln_k, int low_code, int high_code,
                         const std::vector<double>& g_start, int coefficients) {
  EmorFit fit;
  const size_t pixels = codes.size() / n;
  std::vector<double> ln_e(pixels, 0.0);
  ceres::Problem problem;
  problem.AddParameterBlock(fit.c.data(), 6);
  for (size_t p = 0; p < pixels; ++p) {
    double sum = 0.0;
    int good = 0;
    for (size_t j = 0; j < n; ++j) {
      const int z = codes[p * n + j];
      if (z > low_code && z < high_code) sum += g_start[z] - g_start[255] - ln_k[j], ++good;
    }
    if (good < 2) continue;  // one code: its ln E fits it exactly and says nothing of the curve
    ln_e[p] = sum / good;
    for (size_t j = 0; j < n; ++j) {
      const int z = codes[p * n + j];
      if (!(z > low_code && z < high_code)) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CodeResidual, 1, 6, 1>(new CodeResidual{&basis, double(z), ln_k[j]}),
                               new ceres::HuberLoss(3.0), fit.c.data(), &ln_e[p]);
      ++fit.residuals;
    }
  }
  if (fit.residuals < 4 * coefficients) {
    fit.why = "too few well-exposed samples for the EMoR fit (" + std::to_string(fit.residuals) + ")";
    return fit;
  }
  if (coefficients < 6) {
    std::vector<int> held;
    for (int m = coefficients; m < 6; ++m) held.push_back(m);
    problem.SetManifold(fit.c.data(), new ceres::SubsetManifold(6, held));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_SCHUR;
  so.max_num_iterations = 100;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  fit.iterations = static_cast<int>(summary.iterations.size());
  fit.rms_dn = std::sqrt(2.0 * summary.final_cost / fit.residuals);
  // A camera curve increases everywhere; a fit that does not is no camera's.
  const std::vector<double> f = EmorCurve(basis, fit.c);
  for (int k = 1; k < kEmorSamples; ++k)
    if (!(f[k] > f[k - 1])) {
      fit.why = "the fitted EMoR curve is not increasing (at E = " + std::to_string(double(k) / (kEmorSamples - 1)) + ")";
      return fit;
    }
  if (!summary.IsSolutionUsable() || !std::isfinite(fit.rms_dn)) {
    fit.why = "the EMoR fit failed: " + summary.message;
    return fit;
  }
  fit.g = InverseLog(f);
  fit.usable = true;
  return fit;
}

double UndeterminedPeriod(const std::vector<double>& ln_k) {
  std::vector<double> k(ln_k);
  std::sort(k.begin(), k.end());
  std::vector<double> steps;
  for (size_t i = 1; i < k.size(); ++i) steps.push_back(k[i] - k[i - 1]);
  if (steps.empty()) return 0.0;
  const double smallest = *std::min_element(steps.begin(), steps.end());
  for (int m = 1; m <= 8; ++m) {
    const double guess = smallest / m;
    if (guess < 0.25 * std::log(2.0)) break;
    // Each step's multiple of the guess, then the period that fits them best (least
    // squares): nominal shutter speeds (1/15 s for 1/16) make a constant step look uneven.
    double num = 0.0, den = 0.0;
    for (double d : steps) {
      const double n = std::max(1.0, std::round(d / guess));
      num += d * n, den += n * n;
    }
    const double L = num / den;
    bool whole = true;
    for (double d : steps) whole = whole && std::fabs(d - std::max(1.0, std::round(d / guess)) * L) <= 0.05 * L;
    if (whole) return L;
  }
  return 0.0;
}

std::vector<double> AdoptPeriodicPart(const std::vector<double>& g_free, const std::vector<double>& g_prior,
                                      double period, int low_code, int high_code, const std::vector<float>& w) {
  constexpr int kBins = 32;
  auto phase = [&](int z) {
    const double u = (g_free[z] - g_free[128]) / period;
    return (u - std::floor(u)) * kBins;  // [0, kBins)
  };
  std::array<double, kBins> sum{}, weight{};
  for (int z = low_code + 1; z < high_code; ++z) {
    const int b = std::min(kBins - 1, static_cast<int>(phase(z)));
    const double a = double(w[z]) * w[z];
    sum[b] += a * (g_prior[z] - g_free[z]);
    weight[b] += a;
  }
  std::array<double, kBins> p{};
  std::vector<int> filled;
  for (int b = 0; b < kBins; ++b)
    if (weight[b] > 0.0) p[b] = sum[b] / weight[b], filled.push_back(b);
  if (filled.empty()) return g_free;
  for (int b = 0; b < kBins; ++b) {  // empty bins: linear between the filled neighbours, around the circle
    if (weight[b] > 0.0) continue;
    const auto next = std::upper_bound(filled.begin(), filled.end(), b);
    const int hi = next == filled.end() ? filled.front() + kBins : *next;
    const int lo = next == filled.begin() ? filled.back() - kBins : *(next - 1);
    const double t = double(b - lo) / (hi - lo);
    p[b] = p[(lo + kBins) % kBins] * (1.0 - t) + p[hi % kBins] * t;
  }
  std::vector<double> g(256);
  for (int z = 0; z < 256; ++z) {
    const double x = phase(z) - 0.5;  // bin centres at b + 0.5
    const int b0 = static_cast<int>(std::floor(x));
    const double t = x - b0;
    g[z] = g_free[z] + p[(b0 + kBins) % kBins] * (1.0 - t) + p[(b0 + 1) % kBins] * t;
  }
  return g;
}

}  // namespace skycal::capture::detail
