#include "skycal/cloudfit/cloud_lighting_fit.h"

#include <chrono>
#include <cmath>
#include <memory>

#include "cloud_lighting_solve.h"
#include "cloud_lighting_term.h"
#include "fit_term.h"
#include "skycal/capture/cloud_mask.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/fit/sky_fit.h"
#include "sky_fit_terms.h"

namespace skycal::cloudfit {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

void CheckShapes(const KnownCloudShapes& s) {
  if (!s.noise || !s.weather) throw Error("cloud lighting fit: the known shapes need the noise and the weather map");
  clouds::ValidateCloudParams(s.params, "cloud preset");
}

// Every parameter of an unfitted report: held, and why.
void HoldAll(const CloudLighting& l, const std::string& why, CloudLightingReport* r) {
  Conditioning c;
  c.parameters.resize(kCloudLightingParameters);
  for (auto& p : c.parameters) {
    p.held = true;
    p.why = why;
  }
  ReportParameters(l, l, c, r);
}

// The factory of cloud terms: the joint fit builds its cloud term here and nowhere else.
// Part B (unknown shapes: the statistical term over cloud-pixel radiance per angle bin,
// fitted where noise cannot reproduce a photograph's shapes) adds its kind to
// CloudTermKind and one case below; FitSkyAndClouds and the verb need no other change.
std::unique_ptr<fit::FitTerm> MakeCloudTerm(CloudTermKind kind, CloudSampleModel* model, const CloudLighting& initial,
                                            const CloudLightingOptions& o) {
  switch (kind) {
    case CloudTermKind::kKnownShapes:
      return std::make_unique<CloudLightingTerm>(model, initial, o);
  }
  throw Error("cloud lighting fit: unknown cloud term kind");
}

}  // namespace

const char* ToString(CloudMode m) { return m == CloudMode::kAuto ? "auto" : m == CloudMode::kOn ? "on" : "off"; }

CloudMode ParseCloudMode(const std::string& text, const std::string& option) {
  if (text == "auto") return CloudMode::kAuto;
  if (text == "on") return CloudMode::kOn;
  if (text == "off") return CloudMode::kOff;
  throw Error(option + ": unknown mode '" + text + "' (expected auto, on or off)");
}

bool CloudLightingOptions::IsValid(std::string* why) const {
  if (samples < 16 || samples > 1000000) {
    *why = "cloud samples = " + std::to_string(samples) + " (expected an integer in [16, 1000000])";
    return false;
  }
  if (!(cloud_transmittance > 0.0 && cloud_transmittance <= 1.0)) {
    *why = "cloud transmittance threshold = " + FormatNumber(cloud_transmittance) + " (expected in (0, 1])";
    return false;
  }
  if (!(noise_level > 0.0 && noise_level < 1.0) || !(max_predicted_error > 0.0 && max_predicted_error < 10.0)) {
    *why = "cloud noise level and max predicted error must be in (0, 1) and (0, 10)";
    return false;
  }
  if (max_iterations < 1 || max_iterations > 10000 || threads < 1 || threads > 256) {
    *why = "cloud max iterations must be in [1, 10000] and threads in [1, 256]";
    return false;
  }
  for (const std::string& h : hold) {
    if (CloudLightingIndex(h) < 0) {
      std::string names;
      for (const char* n : CloudLightingNames()) names += (names.empty() ? "" : ", ") + std::string(n);
      *why = "--cloud-hold " + h + ": not a cloud lighting parameter (expected one of " + names + ")";
      return false;
    }
  }
  return true;
}

CloudLightingReport FitCloudLightingKnownSky(const ImageRGB& reference, const std::array<double, 3>& sun_dir,
                                             const render::Preset& sky_preset, const ImageRGB& sky, double exposure,
                                             const KnownCloudShapes& shapes, const CloudLightingOptions& o,
                                             clouds::CloudRenderer* renderer) {
  const auto t0 = Clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  CheckShapes(shapes);
  if (sky.width != reference.width || sky.height != reference.height) {
    throw Error("cloud lighting fit: the sky image is not the reference's size");
  }
  std::unique_ptr<clouds::CloudRenderer> cpu;
  clouds::CloudRenderer* images = renderer;
  if (!images) {
    cpu = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble, o.threads);
    images = cpu.get();
  }
  const clouds::CloudRenderRequest request = RequestFor(sun_dir, reference.width, reference.height, shapes);
  const clouds::CloudImage start = images->Render({&sky_preset, &shapes.params, shapes.noise, shapes.weather}, request);
  // Usable: above the horizon (the renderer's own row latitudes), positive and finite.
  const clouds::LatLongTrig trig = clouds::MakeLatLongTrig(reference.width, reference.height);
  std::vector<char> usable(static_cast<size_t>(reference.width) * reference.height, 0);
  for (size_t i = 0; i < usable.size(); ++i) {
    bool ok = trig.sin_lat[i / reference.width] > 0.0;
    for (int c = 0; c < 3; ++c) ok = ok && std::isfinite(reference.pixels[3 * i + c]) && reference.pixels[3 * i + c] > 0.0f;
    usable[i] = ok ? 1 : 0;
  }
  const std::vector<size_t> pixels = CloudPixels(usable, start.transmittance, o.cloud_transmittance);
  if (pixels.empty()) throw Error("cloud lighting fit: the known shapes cover no usable pixel of the reference");

  CloudSampleModel model({sky_preset, shapes.params, shapes.noise, shapes.weather, request},
                         ChooseSamples(pixels, reference, o.samples),
                         renderer ? CloudValueSource::kRenderer : CloudValueSource::kCpuDouble, renderer, o.threads);
  model.SetSky(sky_preset, sky, exposure);
  const CloudLighting initial = GetCloudLighting(shapes.params);
  CloudLightingReport report;
  const auto tc = Clock::now();
  const Conditioning cond = ConditionAt(&model, initial, o);
  report.conditioning_time_s = Seconds(tc);
  CloudLighting theta = initial;
  const ceres::Solver::Summary s = SolveCloudBlock(&model, theta.data(), cond, o);

  ImageRGB sky_exposed = sky;
  for (float& v : sky_exposed.pixels) v = static_cast<float>(v * exposure);
  report.fitted = true;
  report.decision = "fitted with the sky given";
  ReportParameters(initial, theta, cond, &report);
  report.cloud_pixels = static_cast<long long>(pixels.size());
  report.samples = static_cast<int>(model.samples().size());
  report.cloud_initial = CompositeErrors(pixels, reference, Composite(sky_exposed, start, exposure));
  report.fitted_params = shapes.params;
  SetCloudLighting(theta, &report.fitted_params);
  const clouds::CloudImage final_image =
      images->Render({&sky_preset, &report.fitted_params, shapes.noise, shapes.weather}, request);
  report.cloud_final = CompositeErrors(pixels, reference, Composite(sky_exposed, final_image, exposure));
  report.iterations = static_cast<int>(s.iterations.size()) - 1;
  report.termination = ceres::TerminationTypeToString(s.termination_type);
  report.renders = model.renders;
  report.jacobians = model.jacobians;
  report.render_time_s = model.render_time_s;
  report.jacobian_time_s = model.jacobian_time_s;
  report.value_source = renderer ? renderer->Describe() : "cpu double model at the samples";
  report.time_s = Seconds(t0);
  return report;
}

CloudDecision DecideClouds(CloudMode mode, const std::vector<fit::Reference>& refs, const render::Preset& init,
                           bool shapes_given, double min_cloud_fraction) {
  const auto t0 = Clock::now();
  CloudDecision d;
  if (mode == CloudMode::kOff) {
    d.why = "--clouds off: the sky alone is fitted; no cloud is marched";
    return d;
  }
  if (refs.size() != 1) {
    if (mode == CloudMode::kOn) throw Error("--clouds on: the cloud lighting fit takes one reference at a time");
    d.why = "--clouds auto: " + std::to_string(refs.size()) +
            " references (the cloud lighting fit takes one reference at a time): clouds off";
    return d;
  }
  const fit::Reference& ref = refs[0];
  render::RenderRequest req;
  req.sun_dir = ref.sun_dir;
  req.width = ref.radiance.width;
  req.height = ref.radiance.height;
  req.sun_disc = false;
  const ImageRGB clear = render::CreateRenderer(render::Backend::kCpu)->Render(init, req);
  const capture::CloudMask mask = capture::EstimateCloudProbability(ref.radiance, clear, ref.sun_dir, {});
  for (size_t i = 0; i < ref.pixel_class.size(); ++i) {
    if (ref.pixel_class[i] != fit::PixelClass::kSky) continue;
    ++d.sky_pixels;
    if (mask.probability[i] >= 0.5f) ++d.cloudy_pixels;
  }
  d.cloud_fraction = d.sky_pixels > 0 ? static_cast<double>(d.cloudy_pixels) / static_cast<double>(d.sky_pixels) : 0.0;
  d.time_s = Seconds(t0);
  const std::string seen = std::to_string(d.cloudy_pixels) + " of " + std::to_string(d.sky_pixels) +
                           " fitted sky pixels are cloud (" + FormatNumber(100.0 * d.cloud_fraction) +
                           "%, cloud mask probability >= 0.5)";
  if (mode == CloudMode::kOn) {
    if (d.cloudy_pixels == 0) {
      throw Error(ref.path + ": --clouds on but the reference has no cloud pixels (" + seen +
                  "): fit it with --clouds off or auto");
    }
    if (!shapes_given) throw Error("--clouds on needs the cloud shapes: --cloud-preset PRESET.json (a clouds section)");
    d.march = true;
    d.why = "--clouds on: " + seen;
    return d;
  }
  if (d.cloud_fraction < min_cloud_fraction) {
    d.why = "--clouds auto: clear (" + seen + ", below " + FormatNumber(100.0 * min_cloud_fraction) +
            "%): no cloud is marched and every cloud parameter is held";
    return d;
  }
  if (!shapes_given) {
    d.why = "--clouds auto: " + seen +
            ", but no cloud shapes were given (--cloud-preset): the known-shapes term cannot run; clouds off (their "
            "pixels still count in the sky terms)";
    return d;
  }
  d.march = true;
  d.why = "--clouds auto: cloudy (" + seen + "): the cloud lighting joins the fit";
  return d;
}

SkyCloudFit FitSkyAndClouds(const std::vector<fit::Reference>& refs, const render::Preset& init,
                            const fit::FitOptions& fo, render::SkyRenderer& renderer,
                            const std::vector<const fit::ProbeSamples*>& probes, const CloudDecision& decision,
                            CloudTermKind kind, const KnownCloudShapes* shapes, const CloudLightingOptions& o,
                            clouds::CloudRenderer* cloud_renderer) {
  SkyCloudFit out;
  CloudLightingReport& rep = out.clouds;
  rep.decision = decision.why;
  rep.cloud_fraction = decision.cloud_fraction;
  const CloudLighting start = GetCloudLighting(shapes ? shapes->params : clouds::CloudParams{});
  if (!decision.march) {
    out.sky = fit::FitSky(refs, init, fo, renderer, probes);
    HoldAll(start, "clouds not fitted: " + decision.why, &rep);
    if (shapes) rep.fitted_params = shapes->params;
    out.sky.decisions.push_back({"cloud lighting not fitted", decision.why, 0.0,
                                 "none: no cloud term was built, so no cloud render or Jet march ran", std::nullopt, ""});
    return out;
  }
  const auto t0 = Clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (!shapes) throw Error("cloud lighting fit: the known-shapes term needs the shapes (--cloud-preset)");
  if (!cloud_renderer) throw Error("cloud lighting fit: no cloud renderer");
  if (refs.size() != 1) throw Error("cloud lighting fit: one reference at a time");
  CheckShapes(*shapes);
  const fit::Reference& ref = refs[0];
  const clouds::CloudRenderRequest request = RequestFor(ref.sun_dir, ref.radiance.width, ref.radiance.height, *shapes);
  const clouds::CloudImage start_image =
      cloud_renderer->Render({&init, &shapes->params, shapes->noise, shapes->weather}, request);
  std::vector<char> usable(ref.pixel_class.size());
  for (size_t i = 0; i < usable.size(); ++i) usable[i] = ref.pixel_class[i] == fit::PixelClass::kSky ? 1 : 0;
  const std::vector<size_t> pixels = CloudPixels(usable, start_image.transmittance, o.cloud_transmittance);
  if (pixels.empty()) {
    throw Error(ref.path + ": --clouds: the known cloud shapes (--cloud-preset, --cloud-time) cover none of the "
                "reference's fitted sky pixels (transmittance < " + FormatNumber(o.cloud_transmittance) + ")");
  }
  // The cloud pixels leave the sky terms (kUserMasked) and join the cloud term.
  std::vector<fit::Reference> masked = refs;
  for (size_t i : pixels) masked[0].pixel_class[i] = fit::PixelClass::kUserMasked;
  masked[0].counts.sky -= static_cast<long long>(pixels.size());
  masked[0].counts.user_masked += static_cast<long long>(pixels.size());

  CloudSampleModel model({init, shapes->params, shapes->noise, shapes->weather, request},
                         ChooseSamples(pixels, ref.radiance, o.samples), CloudValueSource::kRenderer, cloud_renderer,
                         o.threads);
  std::unique_ptr<fit::FitTerm> term_owner = MakeCloudTerm(kind, &model, start, o);
  auto* term = dynamic_cast<CloudLightingTerm*>(term_owner.get());
  out.sky = fit::FitSkyWithTerms(masked, init, fo, renderer, probes, {term_owner.get()});

  // The final solve of the cloud block with exact Jacobians on the exported sky (after
  // the gauge move: exposure x LUT is what the sky fit fixes, the sun's illuminance is not
  // scaled with it, so the clouds' light is final only now).
  {
    render::RenderRequest req;
    req.sun_dir = ref.sun_dir;
    req.width = ref.radiance.width;
    req.height = ref.radiance.height;
    req.sun_disc = false;
    model.SetSky(out.sky.preset, render::CreateRenderer(render::Backend::kCpu)->Render(out.sky.preset, req),
                 out.sky.references[0].exposure);
    term->Finish(SolveCloudBlock(&model, term->lighting().data(), term->conditioning(), o));
  }
  rep.fitted = true;
  rep.cloud_pixels = static_cast<long long>(pixels.size());
  rep.samples = static_cast<int>(model.samples().size());
  ReportParameters(start, term->lighting(), term->conditioning(), &rep);
  rep.fitted_params = shapes->params;
  SetCloudLighting(term->lighting(), &rep.fitted_params);
  // The outputs: the composite with the fitted clouds over the fitted sky (the sky render
  // already carries the exposure and the sun disc).
  fit::ReferenceFit& rf = out.sky.references[0];
  const clouds::CloudImage final_image =
      cloud_renderer->Render({&out.sky.preset, &rep.fitted_params, shapes->noise, shapes->weather}, request);
  const clouds::CloudImage initial_image =
      cloud_renderer->Render({&out.sky.preset, &shapes->params, shapes->noise, shapes->weather}, request);
  const ImageRGB sky_exposed = rf.rendered;
  rf.rendered = Composite(sky_exposed, final_image, rf.exposure);
  rep.clear.pixels = rf.errors.pixels;
  rep.clear.rel_rmse = rf.errors.rel_rmse;
  rep.clear.log_rmse = rf.errors.log_rmse;
  rf.errors = fit::CompareToReference(ref, rf.rendered);  // the whole sky, cloud pixels included
  rep.cloud_final = CompositeErrors(pixels, ref.radiance, rf.rendered);
  rep.cloud_initial = CompositeErrors(pixels, ref.radiance, Composite(sky_exposed, initial_image, rf.exposure));
  rep.iterations = term->iterations();
  rep.termination = term->termination();
  rep.renders = model.renders;
  rep.jacobians = model.jacobians;
  rep.render_time_s = model.render_time_s;
  rep.jacobian_time_s = model.jacobian_time_s;
  rep.conditioning_time_s = term->conditioning_time_s();
  rep.value_source = cloud_renderer->Describe();
  rep.time_s = Seconds(t0);
  out.sky.decisions.push_back(
      {"sky terms without the cloud pixels",
       std::to_string(pixels.size()) + " pixels whose known-shape transmittance is below " +
           FormatNumber(o.cloud_transmittance) + " are fitted by the cloud term (sky x T + clouds), not the sky rows",
       0.0, "none: a change of objective, not a saving", std::nullopt, ""});
  return out;
}

}  // namespace skycal::cloudfit
