#include "probe_terms.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/error.h"

namespace skycal::fit {
namespace {
constexpr double kPi = 3.14159265358979323846;

double Dot(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Predicted ball radiance (reference units) of sample i for illuminance `sun`.
std::array<double, 3> Predict(const ProbeIrradianceParts& parts, size_t i, const std::array<double, 3>& sun, double k,
                              double albedo) {
  std::array<double, 3> p{};
  for (int c = 0; c < 3; ++c) p[c] = k * albedo / kPi * (parts.ambient[i][c] + sun[c] * parts.sun_factor[i]);
  return p;
}
}  // namespace

std::vector<ProbeFrame> PrepareProbeFrames(const std::vector<Reference>& refs,
                                           const std::vector<const ProbeSamples*>& probes) {
  std::vector<ProbeFrame> frames(refs.size());
  if (probes.empty()) return frames;
  if (probes.size() != refs.size()) {
    throw Error("fit: " + std::to_string(probes.size()) + " probe entries for " + std::to_string(refs.size()) +
                " references (need one per reference, null for none)");
  }
  for (size_t r = 0; r < refs.size(); ++r) {
    if (!probes[r]) continue;
    ProbeFrame& f = frames[r];
    f.probe = probes[r];
    const auto& s = refs[r].sun_dir;
    double pixels = 0.0;
    for (const capture::ProbeSample& smp : probes[r]->samples) {
      bool ok = smp.pixels > 0;
      for (int c = 0; c < 3; ++c) ok = ok && std::isfinite(smp.radiance[c]) && smp.radiance[c] > 0.0 && std::isfinite(smp.normal[c]);
      const double len = std::sqrt(Dot(smp.normal, smp.normal));
      if (!ok || !(len > 0.5)) {
        ++f.dropped;
        continue;
      }
      capture::ProbeSample unit = smp;
      for (double& v : unit.normal) v /= len;
      f.samples.push_back(unit);
      pixels += smp.pixels;
      if (Dot(unit.normal, s) > 0.05) ++f.sun_facing;
      if (unit.normal[1] < -0.1) ++f.ground_facing;
    }
    if (f.samples.empty()) {
      throw Error(probes[r]->path + ": no usable probe sample (every sample has a channel <= 0 or not finite)");
    }
    for (const auto& smp : f.samples) f.pixel_share.push_back(smp.pixels / pixels);
    if (!(s[1] > 0.0)) {
      f.note = "the sun is below the horizon: it does not light the ball";
    } else if (f.sun_facing < 3) {
      f.note = "only " + std::to_string(f.sun_facing) +
               " probe samples face the sun (need 3): the sun lights the ball's far side, not observable from this view";
    } else {
      f.sun_observable = true;
    }
  }
  return frames;
}

std::unique_ptr<ProbeCost> MakeProbeCost(const ProbeFrame& frame, const Reference& ref, const FitState& state,
                                         const FitOptions& o, bool tied_rows, double sky_share,
                                         const std::set<std::pair<int, int>>& parameter_columns, double loss_scale,
                                         std::atomic<long long>* evaluation_ns, std::vector<size_t>* texel_index) {
  ProbeCostSetup setup;
  setup.state = &state;
  setup.tied_rows = tied_rows;
  setup.initial_log_lut = &state.initial_log_lut;
  setup.sun_dir = ref.sun_dir;
  setup.albedo = frame.probe->albedo;
  setup.loss = o.loss;
  setup.loss_scale = loss_scale;
  setup.quadrature_width = o.probe_quadrature_width;
  setup.parameter_columns = parameter_columns;
  setup.evaluation_ns = evaluation_ns;
  for (size_t i = 0; i < frame.samples.size(); ++i) {
    ProbeResidualSample s;
    s.normal = frame.samples[i].normal;
    for (int c = 0; c < 3; ++c) s.log_radiance[c] = std::log(frame.samples[i].radiance[c]);
    s.sqrt_weight = std::sqrt(o.probe_weight * sky_share * frame.pixel_share[i]);
    setup.samples.push_back(s);
  }
  return std::make_unique<ProbeCost>(std::move(setup), texel_index);
}

LinearSun SolveLinearSun(const ProbeIrradianceParts& parts, const ProbeFrame& frame, double log_exposure) {
  LinearSun out;
  if (parts.ambient.size() != frame.samples.size()) return out;  // outside the model's domain
  const double k = std::exp(log_exposure), a = frame.probe->albedo;
  for (int c = 0; c < 3; ++c) {
    double fy = 0.0, ff = 0.0;
    for (size_t i = 0; i < frame.samples.size(); ++i) {
      const double f = parts.sun_factor[i], w = frame.pixel_share[i];
      const double y = kPi * frame.samples[i].radiance[c] / (a * k) - parts.ambient[i][c];
      fy += w * f * y;
      ff += w * f * f;
    }
    out.illuminance[c] = ff > 0.0 ? std::max(0.0, fy / ff) : 0.0;
  }
  out.fraction = SunShare(parts, frame, out.illuminance, log_exposure);
  return out;
}

double SunShare(const ProbeIrradianceParts& parts, const ProbeFrame& frame, const std::array<double, 3>& sun,
                double log_exposure) {
  if (parts.ambient.size() != frame.samples.size()) return 0.0;
  const double k = std::exp(log_exposure), a = frame.probe->albedo;
  std::vector<std::array<double, 3>> sun_radiance(frame.samples.size());
  for (size_t i = 0; i < frame.samples.size(); ++i)
    for (int c = 0; c < 3; ++c) sun_radiance[i][c] = k * a / kPi * sun[c] * parts.sun_direct[i];
  return capture::SunShareOfBrightest(frame.samples, sun_radiance, parts.sun_direct, 0.1);
}

void ProbeFitErrors(const ProbeIrradianceParts& parts, const ProbeFrame& frame, const std::array<double, 3>& sun,
                    double log_exposure, double* residual, double* log_rmse) {
  *residual = *log_rmse = 0.0;
  if (parts.ambient.size() != frame.samples.size()) return;
  double d2 = 0.0, m2 = 0.0, l2 = 0.0;
  for (size_t i = 0; i < frame.samples.size(); ++i) {
    const auto p = Predict(parts, i, sun, std::exp(log_exposure), frame.probe->albedo);
    for (int c = 0; c < 3; ++c) {
      const double m = frame.samples[i].radiance[c];
      d2 += (p[c] - m) * (p[c] - m);
      m2 += m * m;
      const double l = p[c] > 0.0 ? std::log(p[c] / m) : 50.0;
      l2 += l * l;
    }
  }
  *residual = m2 > 0.0 ? std::sqrt(d2 / m2) : 0.0;
  *log_rmse = std::sqrt(l2 / (3.0 * frame.samples.size()));
}

}  // namespace skycal::fit
