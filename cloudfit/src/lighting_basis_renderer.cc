#include "skycal/cloudfit/lighting_basis_renderer.h"

#include <cmath>
#include <cstring>
#include <tuple>

#include "skycal/core/error.h"
#include "skycal/render/preset.h"

namespace skycal::cloudfit {
namespace {

bool IsLinearField(const char* name) {
  return std::strcmp(name, "scattering_albedo") == 0 || std::strcmp(name, "ambient_strength") == 0;
}

// The params with the linear fields zeroed: two renders share a basis when these are equal.
clouds::CloudParams NonLinearPart(const clouds::CloudParams& p) {
  clouds::CloudParams q = p;
  q.scattering_albedo = 0.0;
  q.ambient_strength = 0.0;
  return q;
}

bool SameParams(const clouds::CloudParams& a, const clouds::CloudParams& b) {
  clouds::CloudParams x = a, y = b;
  for (const auto& spec : clouds::CloudParameterSpecs())
    if (!IsLinearField(spec.name) && !(*spec.field(x) == *spec.field(y))) return false;
  return true;
}

auto MarchTie(const clouds::MarchOptions& m) {
  return std::tie(m.steps_zenith, m.steps_horizon, m.light_samples, m.light_step_m, m.far_light_distance_m,
                  m.cone_spread, m.cheap_march, m.cheap_step_factor, m.step_back, m.empty_to_cheap, m.opacity_stop,
                  m.opacity_threshold, m.cheap_light, m.cheap_light_opacity, m.far_light);
}

bool SameRequest(const clouds::CloudRenderRequest& a, const clouds::CloudRenderRequest& b) {
  return a.sun_dir == b.sun_dir && a.width == b.width && a.height == b.height && a.time_s == b.time_s &&
         MarchTie(a.march) == MarchTie(b.march);
}

}  // namespace

LightingBasisCloudRenderer::LightingBasisCloudRenderer(clouds::CloudRenderer& inner, int max_entries)
    : inner_(inner), max_entries_(max_entries) {
  if (max_entries < 1) throw Error("lighting basis renderer: max_entries " + std::to_string(max_entries) + " (expected >= 1)");
}

std::string LightingBasisCloudRenderer::Describe() const {
  return inner_.Describe() + ", albedo and ambient from a cached 3-render basis per draw of shapes";
}

void LightingBasisCloudRenderer::set_sun_scale(double s) {
  if (!(s > 0.0 && std::isfinite(s)))
    throw Error("lighting basis renderer: sun scale " + std::to_string(s) + " (expected a finite number > 0)");
  sun_scale_ = s;
}

LightingBasisCloudRenderer::~LightingBasisCloudRenderer() = default;

// C, D and A of one draw of shapes: three marches.
std::unique_ptr<LightingBasisCloudRenderer::Basis> LightingBasisCloudRenderer::March(
    const clouds::CloudScene& scene, const clouds::CloudRenderRequest& request) {
  auto b = std::make_unique<Basis>();
  b->scene = scene;
  b->params = NonLinearPart(*scene.params);
  b->scene.params = &b->params;
  b->request = request;
  clouds::CloudParams c = b->params, d = b->params, a = b->params;  // a = 0, k = 0: C
  d.scattering_albedo = 1.0;                                          // a = 1, k = 0: C + D
  a.scattering_albedo = 1.0;                                          // a = 1, k = 1: C + D + A
  a.ambient_strength = 1.0;
  std::vector<clouds::CloudImage> images = inner_.RenderEach(scene, {&c, &d, &a}, request);  // one submission
  b->c = std::move(images[0]);
  b->d = std::move(images[1]);
  b->a = std::move(images[2]);
  marches_ += 3;
  auto& cp = b->c.radiance.pixels;
  auto& dp = b->d.radiance.pixels;
  auto& ap = b->a.radiance.pixels;
  for (size_t i = 0; i < cp.size(); ++i) {
    ap[i] -= dp[i];  // A
    dp[i] -= cp[i];  // D
  }
  return b;
}

clouds::CloudImage LightingBasisCloudRenderer::Render(const clouds::CloudScene& scene,
                                                      const clouds::CloudRenderRequest& request) {
  if (!scene.params) throw Error("cloud render: incomplete scene");
  clouds::ValidateCloudParams(*scene.params, "cloud parameters");  // the values the basis is weighted by
  Basis* basis = nullptr;
  for (auto& b : cache_)
    if (b->scene.preset == scene.preset && b->scene.noise == scene.noise && b->scene.weather == scene.weather &&
        SameParams(b->params, *scene.params) && SameRequest(b->request, request)) {
      basis = b.get();
      break;
    }
  if (!basis) {
    auto b = March(scene, request);
    if (static_cast<int>(cache_.size()) >= max_entries_) cache_.erase(cache_.begin());
    cache_.push_back(std::move(b));
    basis = cache_.back().get();
  } else {
    ++synthesized_;
  }
  if (sun_scale_ != 1.0 && !basis->half) {
    basis->half_sun = std::make_unique<render::Preset>(*basis->scene.preset);
    basis->half_sun->sun_illuminance_lux *= 0.5;
    clouds::CloudScene half = basis->scene;
    half.preset = basis->half_sun.get();
    basis->half = March(half, basis->request);
  }
  const double a = scene.params->scattering_albedo, ak = a * scene.params->ambient_strength;
  clouds::CloudImage out;
  out.radiance = basis->c.radiance;
  out.transmittance = basis->c.transmittance;  // the extinction's alone: the same in all three
  out.full_samples = basis->c.full_samples;
  auto& op = out.radiance.pixels;
  const auto& dp = basis->d.radiance.pixels;
  const auto& ap = basis->a.radiance.pixels;
  const double t = 2.0 * (sun_scale_ - 1.0);  // L(s E) = L(E) + t (L(E) - L(E / 2))
  const Basis* h = sun_scale_ != 1.0 ? basis->half.get() : nullptr;
  for (size_t i = 0; i < op.size(); ++i) {
    const double full = op[i] + a * dp[i] + ak * ap[i];
    if (!h) {
      op[i] = static_cast<float>(full);
      continue;
    }
    const double half = h->c.radiance.pixels[i] + a * h->d.radiance.pixels[i] + ak * h->a.radiance.pixels[i];
    op[i] = static_cast<float>(full + t * (full - half));
  }
  return out;
}

}  // namespace skycal::cloudfit
