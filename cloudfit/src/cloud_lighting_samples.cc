#include "cloud_lighting_samples.h"

#include <ceres/jet.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "skycal/core/error.h"

namespace skycal::cloudfit {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

// The sun's part of the shade at `scale` (CloudParams::sun_scale): the direct sun and the
// sunlit part of the ground's radiance (`sun`, `ground_sun`: per unit scale; `ground_sky`: the
// sky-lit part).
template <typename Shade, typename S>
void SetShadeSun(const S& scale, const glsl::Vec3<double>& sun, const glsl::Vec3<double>& ground_sun,
                 const glsl::Vec3<double>& ground_sky, Shade* s) {
  s->sun_illuminance.x = scale * sun.x;
  s->sun_illuminance.y = scale * sun.y;
  s->sun_illuminance.z = scale * sun.z;
  s->ground_radiance.x = ground_sky.x + scale * ground_sun.x;
  s->ground_radiance.y = ground_sky.y + scale * ground_sun.y;
  s->ground_radiance.z = ground_sky.z + scale * ground_sun.z;
}

// The shade's lighting fields in CloudLightingNames() order (cloud_lighting_params.cc):
// the one place that maps the fitted block onto the model's CloudShadeParams. The sun's
// scale multiplies the direct sun and the sunlit part of the ground's radiance (`sun`,
// `ground_sun`, `ground_sky`: those parts per unit scale, resolved in double).
template <typename Shade, typename S>
void SetShadeLighting(const S* t, const glsl::Vec3<double>& sun, const glsl::Vec3<double>& ground_sun,
                      const glsl::Vec3<double>& ground_sky, Shade* s) {
  s->extinction = t[0];
  s->albedo = t[1];
  s->g1 = t[2];
  s->g2 = t[3];
  s->phase_blend = t[4];
  s->powder_strength = t[5];
  s->powder_view_fade = t[6];
  s->rain_absorption = t[7];
  s->ambient_strength = t[8];
  s->ambient_height_bias = t[9];
  s->ground_bounce = t[10];
  s->ms_a = t[11];
  s->ms_b = t[12];
  s->ms_c = t[13];
  SetShadeSun(t[14], sun, ground_sun, ground_sky, s);
}

// Runs f(i) for i in [0, n) over `threads` workers (interleaved: neighbouring samples cost
// alike, so the workers finish together).
template <typename F>
void ParallelFor(size_t n, int threads, F f) {
  const int t = std::max(1, std::min<int>(threads, static_cast<int>(n)));
  std::vector<std::thread> pool;
  auto work = [&](int first) {
    for (size_t i = first; i < n; i += t) f(i);
  };
  for (int k = 1; k < t; ++k) pool.emplace_back(work, k);
  work(0);
  for (auto& th : pool) th.join();
}

}  // namespace

CloudSampleModel::CloudSampleModel(CloudSampleScene scene, std::vector<CloudSample> samples, CloudValueSource source,
                                   clouds::CloudRenderer* renderer, int threads)
    : scene_(std::move(scene)),
      samples_(std::move(samples)),
      source_(source),
      renderer_(renderer),
      threads_(std::max(1, threads)),
      textures_(*scene_.noise, *scene_.weather) {
  for (int k = 0; k < kCloudLightingParameters; ++k) free_.push_back(k);
  if (samples_.empty()) throw Error("cloud lighting fit: no cloud pixels to fit");
  if (source_ == CloudValueSource::kRenderer && !renderer_) throw Error("cloud lighting fit: no renderer for the values");
  const clouds::LatLongTrig trig = clouds::MakeLatLongTrig(scene_.request.width, scene_.request.height);
  for (const CloudSample& s : samples_) {
    if (s.x < 0 || s.y < 0 || s.x >= scene_.request.width || s.y >= scene_.request.height) {
      throw Error("cloud lighting fit: sample pixel outside the frame");
    }
    const double cl = trig.cos_lat[s.y];
    views_.push_back({trig.sin_lon[s.x] * cl, trig.sin_lat[s.y], trig.cos_lon[s.x] * cl});
  }
  ResolveShade();
}

void CloudSampleModel::ResolveShade() {
  clouds::CloudParams p = scene_.params;
  p.sun_scale = 1.0;
  const clouds::CloudShadeD one = clouds::ResolveCloudShade({&scene_.sky_preset, &p, scene_.noise, scene_.weather}, scene_.request);
  p.sun_scale = 2.0;
  const clouds::CloudShadeD two = clouds::ResolveCloudShade({&scene_.sky_preset, &p, scene_.noise, scene_.weather}, scene_.request);
  sun_per_scale_ = one.sun_illuminance;
  ground_sun_per_scale_ = two.ground_radiance - one.ground_radiance;
  ground_sky_ = one.ground_radiance - ground_sun_per_scale_;
  shade_ = one;  // the same but for the sun's scale (the sky's SH-9 rendered twice, not three times)
  SetShadeSun(scene_.params.sun_scale, sun_per_scale_, ground_sun_per_scale_, ground_sky_, &shade_);
}

void CloudSampleModel::SetSky(const render::Preset& sky_preset, const ImageRGB& sky_image, double exposure) {
  if (sky_image.width != scene_.request.width || sky_image.height != scene_.request.height) {
    throw Error("cloud lighting fit: the sky image is not the reference's size");
  }
  scene_.sky_preset = sky_preset;
  ResolveShade();
  exposure_ = exposure;
  for (CloudSample& s : samples_) {
    const size_t i = static_cast<size_t>(s.y) * sky_image.width + s.x;
    for (int c = 0; c < 3; ++c) s.sky[c] = sky_image.pixels[3 * i + c];
  }
  // Every value depends on the sky and the exposure: nothing cached survives a new one.
  cached_theta_.clear();
  jet_theta_.clear();
  images_.clear();
}

void CloudSampleModel::SetFreeParameters(const std::vector<int>& free) {
  for (int k : free)
    if (k < 0 || k >= kCloudLightingParameters) throw Error("cloud lighting fit: a free parameter index out of range");
  if (free == free_) return;
  // A kept Jacobian with every wanted column (the conditioning's, at the solve's start)
  // still serves: the extra columns are held parameters', which the solve's manifold drops.
  const bool subset = std::all_of(free.begin(), free.end(), [&](int k) {
    return std::find(free_.begin(), free_.end(), k) != free_.end();
  });
  free_ = free;
  if (!subset) jet_theta_.clear();
}

bool CloudSampleModel::Evaluate(const double* theta, double* log_model, double* jacobian) {
  if (jacobian) {
    const size_t n = residuals() * kCloudLightingParameters;
    if (jet_theta_.size() != kCloudLightingParameters || !std::equal(jet_theta_.begin(), jet_theta_.end(), theta)) {
      const auto t0 = Clock::now();
      jet_log_.assign(residuals(), 0.0);
      jet_jacobian_.assign(n, 0.0);
      if (!JetValues(theta, jet_log_.data(), jet_jacobian_.data())) {
        jet_theta_.clear();
        return false;
      }
      ++jacobians;
      jacobian_time_s += Seconds(t0);
      jet_theta_.assign(theta, theta + kCloudLightingParameters);
    }
    std::copy(jet_log_.begin(), jet_log_.end(), log_model);
    std::copy(jet_jacobian_.begin(), jet_jacobian_.end(), jacobian);
  }
  if (source_ == CloudValueSource::kCpuDouble) return jacobian ? true : DoubleValues(theta, log_model);
  return RenderValues(theta, log_model);
}

const clouds::CloudImage* CloudSampleModel::RenderedAt(const double* theta) const {
  for (const auto& [t, image] : images_) {
    if (std::equal(t.begin(), t.end(), theta)) return &image;
  }
  return nullptr;
}

void CloudSampleModel::KeepRendered(const double* theta, clouds::CloudImage image) {
  if (images_.size() == kKeptImages) images_.erase(images_.begin() + 1);  // keep the first
  images_.emplace_back(std::vector<double>(theta, theta + kCloudLightingParameters), std::move(image));
}

bool CloudSampleModel::RenderValues(const double* theta, double* log_model) {
  const size_t n3 = residuals();
  if (cached_theta_.size() == kCloudLightingParameters &&
      std::equal(cached_theta_.begin(), cached_theta_.end(), theta)) {
    std::copy(cached_log_.begin(), cached_log_.end(), log_model);
    return true;
  }
  const auto t0 = Clock::now();
  clouds::CloudParams params = scene_.params;
  CloudLighting l{};
  std::copy(theta, theta + kCloudLightingParameters, l.begin());
  SetCloudLighting(l, &params);
  clouds::CloudImage img = renderer_->Render({&scene_.sky_preset, &params, scene_.noise, scene_.weather}, scene_.request);
  ++renders;
  render_time_s += Seconds(t0);
  cached_log_.assign(n3, 0.0);
  bool ok = true;
  for (size_t k = 0; k < samples_.size(); ++k) {
    const CloudSample& s = samples_[k];
    const size_t i = static_cast<size_t>(s.y) * scene_.request.width + s.x;
    const double t = img.transmittance[i];
    for (int c = 0; c < 3; ++c) {
      const double m = exposure_ * (s.sky[c] * t + img.radiance.pixels[3 * i + c]);
      ok = ok && std::isfinite(m) && m > 0.0;
      cached_log_[3 * k + c] = ok ? std::log(m) : 0.0;
    }
  }
  KeepRendered(theta, std::move(img));
  if (!ok) {
    cached_theta_.clear();
    return false;
  }
  cached_theta_.assign(theta, theta + kCloudLightingParameters);
  std::copy(cached_log_.begin(), cached_log_.end(), log_model);
  return true;
}

bool CloudSampleModel::DoubleValues(const double* theta, double* log_model) const {
  clouds::CloudShadeD shade = shade_;
  SetShadeLighting(theta, sun_per_scale_, ground_sun_per_scale_, ground_sky_, &shade);
  std::vector<char> ok(samples_.size(), 1);
  ParallelFor(samples_.size(), threads_, [&](size_t k) {
    clouds::CloudModelD m(textures_);
    const auto& v = views_[k];
    const auto r = m.cloud_march(glsl::Vec3<double>(v[0], v[1], v[2]), shade);
    const double rad[3] = {r.radiance.x, r.radiance.y, r.radiance.z};
    for (int c = 0; c < 3; ++c) {
      const double mv = exposure_ * (samples_[k].sky[c] * r.transmittance + rad[c]);
      if (!(std::isfinite(mv) && mv > 0.0)) ok[k] = 0;
      log_model[3 * k + c] = ok[k] ? std::log(mv) : 0.0;
    }
  });
  for (char o : ok) {
    if (!o) return false;
  }
  return true;
}

bool CloudSampleModel::JetValues(const double* theta, double* log_model, double* jacobian) const {
  const size_t n = free_.size();
  if (n <= 2) return JetValuesOf<2>(theta, log_model, jacobian);
  if (n <= 4) return JetValuesOf<4>(theta, log_model, jacobian);
  if (n <= 8) return JetValuesOf<8>(theta, log_model, jacobian);
  if (n <= 12) return JetValuesOf<12>(theta, log_model, jacobian);  // the released holds' solve frees 9-12
  return JetValuesOf<kCloudLightingParameters>(theta, log_model, jacobian);
}

// The march on Jets of N dual parts, part s the derivative by parameter free_[s] (the held
// parameters constants); their Jacobian columns filled, the others left as they are (0).
template <int N>
bool CloudSampleModel::JetValuesOf(const double* theta, double* log_model, double* jacobian) const {
  using J = ceres::Jet<double, N>;
  using Model = clouds::CloudModel<J, clouds::CpuCloudTextures>;
  auto shade = clouds::CastCloudShade<typename Model::CloudShadeParams>(shade_);
  J t[kCloudLightingParameters];
  for (int k = 0; k < kCloudLightingParameters; ++k) t[k] = J(theta[k]);
  for (size_t s = 0; s < free_.size(); ++s) t[free_[s]] = J(theta[free_[s]], static_cast<int>(s));
  SetShadeLighting(t, sun_per_scale_, ground_sun_per_scale_, ground_sky_, &shade);
  std::vector<char> ok(samples_.size(), 1);
  ParallelFor(samples_.size(), threads_, [&](size_t k) {
    Model m(textures_);
    const auto& v = views_[k];
    const auto r = m.cloud_march(glsl::Vec3<J>(J(v[0]), J(v[1]), J(v[2])), shade);
    const J rad[3] = {r.radiance.x, r.radiance.y, r.radiance.z};
    for (int c = 0; c < 3; ++c) {
      const J mv = exposure_ * (samples_[k].sky[c] * r.transmittance + rad[c]);
      if (!(std::isfinite(mv.a) && mv.a > 0.0)) {
        ok[k] = 0;
        continue;
      }
      const J lg = log(mv);
      const size_t row = 3 * k + c;
      log_model[row] = lg.a;
      for (size_t s = 0; s < free_.size(); ++s) jacobian[row * kCloudLightingParameters + free_[s]] = lg.v[s];
    }
  });
  for (char o : ok) {
    if (!o) return false;
  }
  return true;
}

}  // namespace skycal::cloudfit
