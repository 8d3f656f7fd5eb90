// The sun's illuminance from the gray diffuse probe, after the sky fit (DESIGN.md 1.3,
// Debevec et al. 2003).
//
// Why this is sequential and still exact for the sky. The joint problem would minimise
// sky residuals (reference pixels) + probe residuals over (sky, E_sun). The sun's disc
// and a cone around it are masked out of the reference's sky pixels (PixelClass::kSunCone)
// and the sky renders of the objective have no disc, so no sky residual depends on the
// sun term: the sky part of the joint optimum is the sky-only optimum that FitSky finds.
// The probe residual R_i - albedo/pi (E_sky(n_i) + E_sun max(0, n_i.s)) depends on the sky
// only through E_sky(n_i), which the fitted sky gives, and is linear in E_sun: given the
// fitted sky, its minimiser is the closed-form least squares of capture::RecoverSun. So
// the sequential solve reaches the joint optimum without any relative weighting of probe
// against sky residuals: no weight is needed in the sequential form (a weight would only
// matter if probe residuals were allowed to pull the sky, which we do not do: the sky
// pixels measure the sky far better than a few dozen ball bins).
//
// One approximation remains: below the horizon the model's ground is lit by the model's
// own sun (GroundMode::kLit with the preset's current sun_tint_rgb), so E_sky of normals
// that see the ground uses the starting tint, not the recovered one; with ground albedo
// 0.1 that is a small second-order term (and exact when the tint does not change).
#include "sun_from_probe.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/render/irradiance.h"

namespace skycal::fit {

ProbeSamples ProbeSamplesFromJson(const nlohmann::json& doc, const std::string& origin) {
  auto fail = [&](const std::string& what) -> void { throw Error(origin + ": " + what); };
  if (!doc.is_object() || doc.value("format", std::string()) != "skycal-probe-samples") {
    fail("not a probe samples file (expected \"format\": \"skycal-probe-samples\")");
  }
  if (doc.value("format_version", 0) != 1) fail("unsupported format_version (expected 1)");
  ProbeSamples p;
  p.path = origin;
  try {
    p.albedo = doc.at("albedo").get<double>();
    if (doc.contains("max_luminance") && doc["max_luminance"].is_number()) p.max_luminance = doc["max_luminance"].get<double>();
    p.max_luminance_clipped = doc.value("max_luminance_clipped", false);
    for (const auto& s : doc.at("samples")) {
      capture::ProbeSample ps;
      ps.normal = s.at("normal").get<std::array<double, 3>>();
      ps.radiance = s.at("radiance").get<std::array<double, 3>>();
      ps.pixels = s.value("pixels", 1);
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(ps.normal[c]) || !std::isfinite(ps.radiance[c])) fail("non-finite sample");
      }
      p.samples.push_back(ps);
    }
  } catch (const nlohmann::json::exception& e) {
    fail(std::string("malformed samples: ") + e.what());
  }
  if (!(p.albedo > 0.0 && p.albedo <= 1.0)) fail("albedo must be in (0, 1]");
  if (p.samples.empty()) fail("no samples");
  return p;
}

ProbeSamples LoadProbeSamples(const std::string& path) { return ProbeSamplesFromJson(ReadJsonFile(path), path); }

ProbeSun SunFromProbe(const Reference& ref, const ReferenceFit& rf, const render::Preset& fitted,
                      const ProbeSamples& probe, render::SkyRenderer& renderer, int sky_width) {
  render::RenderRequest req;
  req.sun_dir = ref.sun_dir;
  req.width = sky_width;
  req.height = sky_width / 2;
  req.sun_disc = false;  // the sun enters analytically (render/irradiance.h: a disc would alias)
  req.ground = render::GroundMode::kLit;
  const ImageRGB sky = renderer.Render(fitted, req);
  std::vector<render::Dir3> normals;
  for (const auto& s : probe.samples) normals.push_back(s.normal);
  std::vector<render::Rgb> e_sky = render::IrradianceQuadrature(sky, normals);
  for (auto& e : e_sky) {
    for (double& v : e) v *= rf.exposure;  // model units -> the reference's units
  }
  const capture::SunRecovery rec =
      capture::RecoverSun(probe.samples, {probe.albedo, probe.albedo, probe.albedo}, e_sky, ref.sun_dir);
  ProbeSun out;
  out.visible = rec.visible;
  out.illuminance_ref = rec.sun_illuminance;
  for (int c = 0; c < 3; ++c) {
    out.illuminance_model[c] = rec.sun_illuminance[c] / rf.exposure;
    out.fitted_model[c] = rec.fitted_sun_illuminance[c] / rf.exposure;
  }
  out.lux = Rec709Luminance(out.illuminance_model);
  out.fraction = rec.sun_fraction;
  out.residual = rec.residual_rms_rel;
  out.samples = rec.samples_used;
  out.sun_facing_samples = rec.sun_facing_samples;
  return out;
}

std::array<double, 3> SunTintFor(const render::Preset& preset, const std::array<double, 3>& sun_dir,
                                 const std::array<double, 3>& illuminance_model, bool* clamped) {
  double lo = 0.0, hi = 10.0;
  for (const auto& spec : render::PresetParameterSpecs()) {
    if (std::string(spec.name) == "sun_tint_rgb") lo = spec.min, hi = spec.max;
  }
  const double n = std::sqrt(sun_dir[0] * sun_dir[0] + sun_dir[1] * sun_dir[1] + sun_dir[2] * sun_dir[2]);
  const double zenith = std::acos(std::clamp(sun_dir[1] / n, -1.0, 1.0));
  const auto t = render::SunTransmittance(preset.luts, zenith);
  std::array<double, 3> tint{};
  bool any = false;
  for (int c = 0; c < 3; ++c) {
    const double denom = preset.sun_illuminance_lux * t[c];
    double v = denom > 0.0 ? illuminance_model[c] / denom : hi;
    if (!std::isfinite(v) || v < lo || v > hi) {
      v = std::clamp(std::isfinite(v) ? v : hi, lo, hi);
      any = true;
    }
    tint[c] = v;
  }
  if (clamped) *clamped = any;
  return tint;
}

}  // namespace skycal::fit
