#include "skycal/cloudfit/cloud_lighting_fit.h"

#include <chrono>
#include <cmath>
#include <memory>

#include "cloud_lighting_solve.h"
#include "skycal/capture/cloud_mask.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/renderer.h"

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

// The usable pixels whose known-shape transmittance at the start is below the threshold.
std::vector<size_t> CloudPixelsOf(const std::vector<char>& usable, const clouds::CloudImage& start, double threshold) {
  return CloudPixels(usable, start.transmittance, threshold);
}

// One reference of the cloud solve: its cloud pixels, the sample model on its sky, and
// what its report needs.
struct Member {
  std::string name;
  std::optional<double> time_h;
  const ImageRGB* reference = nullptr;
  std::vector<size_t> pixels;
  std::unique_ptr<CloudSampleModel> model;
  render::Preset sky_preset;
  ImageRGB sky;          // the fitted sky without the disc (the model's), unexposed
  ImageRGB sky_exposed;  // the sky behind the clouds x the exposure
  double exposure = 1.0;
  clouds::CloudRenderRequest request;
};

// The day's hold set: a parameter some reference cannot separate is held in every one
// (the keyframes share their columns, and the prior would otherwise tie a free key to a
// held one), the why naming that reference when there are several.
std::vector<Conditioning> DayConditioning(const std::vector<Conditioning>& each, const std::vector<Member>& m) {
  std::vector<Conditioning> out = each;
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    for (size_t r = 0; r < each.size(); ++r) {
      if (!each[r].parameters[k].held) continue;
      const std::string why = each.size() > 1 ? m[r].name + ": " + each[r].parameters[k].why : each[r].parameters[k].why;
      for (Conditioning& c : out) {
        if (!c.parameters[k].held || c.parameters[k].why.empty()) c.parameters[k].why = why;
        c.parameters[k].held = true;
      }
      break;
    }
  }
  return out;
}

// One reference's solves after the first (CloudLightingOptions): each free parameter left at a
// bound solved again from the far side (restart_at_bounds), then the inseparable holds released
// and the solve continued (release_inseparable). `*c`, `*theta` and `*s` become the kept solve's.
struct SolvedAgain {
  BoundRestarts restarts;
  ReleasedHolds released;
};
SolvedAgain SolveAgain(CloudSampleModel* model, const CloudLighting& start, const CloudLightingOptions& o,
                       Conditioning* c, CloudLighting* theta, ceres::Solver::Summary* s) {
  SolvedAgain r;
  double cost = s->final_cost;
  std::vector<ceres::Solver::Summary> solves;
  if (o.restart_at_bounds) {
    std::vector<char> held(kCloudLightingParameters);
    for (int k = 0; k < kCloudLightingParameters; ++k) held[k] = c->parameters[k].held;
    r.restarts = RestartAtBounds(start, held, [&](CloudLighting* t) {
      solves.push_back(SolveCloudBlock(model, t->data(), *c, o, start));
      return solves.back().final_cost;
    }, theta, &cost);
    if (r.restarts.kept >= 0) *s = solves[static_cast<size_t>(r.restarts.kept)];
  }
  if (o.release_inseparable) {
    r.released = ReleaseInseparableHolds([&](const Conditioning& freed, CloudLighting* t) {
      solves.push_back(SolveCloudBlock(model, t->data(), freed, o, start));
      return solves.back().final_cost;
    }, c, theta, &cost);
    if (r.released.kept) *s = solves.back();
  }
  return r;
}

// The members' solve: their conditioning at the start, the day's hold set, the lighting found
// per member, the solver's summary, the solves after the first and the stage times.
struct Solved {
  std::vector<Conditioning> day;
  std::vector<CloudLighting> theta;
  ceres::Solver::Summary summary;
  SolvedAgain again;
  int prior_residuals = 0;
  int iterations = 0;  // over the solves (a refinement's included)
  double conditioning_s = 0.0, solve_s = 0.0;
};

// Conditions every member at `start` and solves their blocks (one problem; the day's prior
// with three or more).
Solved SolveMembers(std::vector<Member>& m, const CloudLighting& start, const CloudLightingOptions& o) {
  const auto t0 = Clock::now();
  Solved r;
  std::vector<Conditioning> each;
  for (Member& x : m) each.push_back(ConditionAt(x.model.get(), start, o));
  r.conditioning_s = Seconds(t0);
  r.day = DayConditioning(each, m);
  r.theta.assign(m.size(), start);
  std::vector<CloudSampleModel*> models;
  std::vector<double*> blocks;
  std::vector<double> times;
  for (size_t k = 0; k < m.size(); ++k) {
    models.push_back(m[k].model.get());
    blocks.push_back(r.theta[k].data());
    times.push_back(m[k].time_h.value_or(0.0));
  }
  CloudLighting scale{};
  for (int k = 0; k < kCloudLightingParameters; ++k) scale[k] = r.day[0].parameters[k].scale;
  r.summary = SolveCloudDay(models, blocks, r.day[0], times, scale, o, &r.prior_residuals, &start);
  if (m.size() == 1) r.again = SolveAgain(models[0], start, o, &r.day[0], &r.theta[0], &r.summary);
  r.iterations = static_cast<int>(r.summary.iterations.size()) - 1;
  r.solve_s = Seconds(t0);
  return r;
}

// One report per member of the solve: its parameters, and the composites' errors at the start
// and the end. `images` renders what the members' models did not already render.
std::vector<CloudLightingReport> ReportMembers(std::vector<Member>& m, const CloudLighting& start, const Solved& v,
                                               const KnownCloudShapes& shapes, clouds::CloudRenderer* images,
                                               const std::string& decision) {
  const auto tr = Clock::now();
  std::vector<CloudLightingReport> out(m.size());
  for (size_t r = 0; r < m.size(); ++r) {
    CloudLightingReport& rep = out[r];
    Member& x = m[r];
    rep.fitted = true;
    rep.decision = decision;
    rep.reference = x.name;
    rep.time_of_day_h = x.time_h;
    ReportParameters(start, v.theta[r], v.day[r], &rep);
    rep.cloud_pixels = static_cast<long long>(x.pixels.size());
    rep.samples = static_cast<int>(x.model->samples().size());
    rep.fitted_params = shapes.params;
    SetCloudLighting(v.theta[r], &rep.fitted_params);
    auto composite = [&](const CloudLighting& l, const clouds::CloudParams& params) {
      if (!x.model->RenderedAt(l.data()))  // kept: the outputs' composite reuses the fitted one
        x.model->KeepRendered(l.data(), images->Render({&x.sky_preset, &params, shapes.noise, shapes.weather}, x.request));
      return Composite(x.sky_exposed, *x.model->RenderedAt(l.data()), x.exposure);
    };
    rep.cloud_initial = CompositeErrors(x.pixels, *x.reference, composite(start, shapes.params));
    rep.cloud_final = CompositeErrors(x.pixels, *x.reference, composite(v.theta[r], rep.fitted_params));
    rep.iterations = v.iterations;
    rep.bound_restarts = v.again.restarts.tried;
    rep.bound_restart_kept = v.again.restarts.kept >= 0 ? v.again.restarts.parameter : "";
    rep.released_holds = v.again.released.names;
    rep.released_kept = v.again.released.kept;
    rep.released_cost_before = v.again.released.cost_before;
    rep.released_cost_after = v.again.released.cost_after;
    rep.termination = ceres::TerminationTypeToString(v.summary.termination_type);
    rep.renders = x.model->renders;
    rep.jacobians = x.model->jacobians;
    rep.render_time_s = x.model->render_time_s;
    rep.jacobian_time_s = x.model->jacobian_time_s;
    rep.conditioning_time_s = v.conditioning_s;
    rep.solve_time_s = v.solve_s;
    rep.prior_residuals = v.prior_residuals;
    rep.value_source = x.model->source() == CloudValueSource::kRenderer
                           ? images->Describe()
                           : "cpu double model at the samples (renders by " + images->Describe() + ")";
  }
  const double report_s = Seconds(tr);
  for (CloudLightingReport& rep : out) rep.report_time_s = report_s;
  return out;
}

// Usable for the sky-given entry points: above the horizon (the renderer's own row
// latitudes), positive and finite in every channel.
std::vector<char> UsableAboveHorizon(const ImageRGB& reference) {
  const clouds::LatLongTrig trig = clouds::MakeLatLongTrig(reference.width, reference.height);
  std::vector<char> usable(static_cast<size_t>(reference.width) * reference.height, 0);
  for (size_t i = 0; i < usable.size(); ++i) {
    bool ok = trig.sin_lat[i / reference.width] > 0.0;
    for (int c = 0; c < 3; ++c) ok = ok && std::isfinite(reference.pixels[3 * i + c]) && reference.pixels[3 * i + c] > 0.0f;
    usable[i] = ok ? 1 : 0;
  }
  return usable;
}

ImageRGB Exposed(const ImageRGB& sky, double exposure) {
  ImageRGB out = sky;
  for (float& v : out.pixels) v = static_cast<float>(v * exposure);
  return out;
}

// Times of day of a day's members: distinct (the prior divides by their differences).
void CheckDayTimes(const std::vector<Member>& m) {
  if (m.size() < 2) return;
  for (size_t a = 0; a < m.size(); ++a) {
    if (!m[a].time_h) {
      throw Error(m[a].name + ": a day of cloudy references needs each one's time of day (the smoothness prior's axis): "
                  "the EXR attribute skycalTimeOfDay (render --time-of-day, capture --time)");
    }
    for (size_t b = 0; b < a; ++b) {
      if (*m[a].time_h == *m[b].time_h) {
        throw Error(m[b].name + " and " + m[a].name + " have the same time of day " + FormatNumber(*m[a].time_h) +
                    " h (one cloud keyframe per time)");
      }
    }
  }
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
    *why = "CloudLightingOptions::samples = " + std::to_string(samples) + " (expected an integer in [16, 1000000])";
    return false;
  }
  if (!(cloud_transmittance > 0.0 && cloud_transmittance <= 1.0)) {
    *why = "CloudLightingOptions::cloud_transmittance = " + FormatNumber(cloud_transmittance) + " (expected in (0, 1])";
    return false;
  }
  if (!(noise_level > 0.0 && noise_level < 1.0) || !(max_predicted_error > 0.0 && max_predicted_error < 10.0)) {
    *why = "CloudLightingOptions::noise_level = " + FormatNumber(noise_level) + ", max_predicted_error = " +
           FormatNumber(max_predicted_error) + " (expected in (0, 1) and (0, 10))";
    return false;
  }
  if (!(start_prior >= 0.0 && start_prior <= 1e6)) {
    *why = "CloudLightingOptions::start_prior = " + FormatNumber(start_prior) + " (expected a weight in [0, 1e6])";
    return false;
  }
  if (!(day_smoothness >= 0.0 && day_smoothness <= 1e6)) {
    *why = "CloudLightingOptions::day_smoothness = " + FormatNumber(day_smoothness) + " (expected a weight in [0, 1e6])";
    return false;
  }
  if (max_iterations < 1 || max_iterations > 10000 || threads < 1 || threads > 256) {
    *why = "CloudLightingOptions::max_iterations = " + std::to_string(max_iterations) + ", threads = " +
           std::to_string(threads) + " (expected [1, 10000] and [1, 256])";
    return false;
  }
  if (iterations_after_refinement < 1 || iterations_after_refinement > 10000) {
    *why = "CloudLightingOptions::iterations_after_refinement = " + std::to_string(iterations_after_refinement) +
           " (expected an integer in [1, 10000])";
    return false;
  }
  for (const std::string& h : hold) {
    if (CloudLightingIndex(h) < 0) {
      std::string names;
      for (const char* n : CloudLightingNames()) names += (names.empty() ? "" : ", ") + std::string(n);
      *why = "CloudLightingOptions::hold = " + h + ": not a cloud lighting parameter (expected one of " + names + ")";
      return false;
    }
  }
  return true;
}

CloudLightingReport FitCloudLightingKnownSky(const ImageRGB& reference, const std::array<double, 3>& sun_dir,
                                             const render::Preset& sky_preset, const ImageRGB& sky, double exposure,
                                             const KnownCloudShapes& shapes, const CloudLightingOptions& o,
                                             clouds::CloudRenderer* renderer) {
  DayReference d;
  d.reference = &reference;
  d.sun_dir = sun_dir;
  d.sky_preset = &sky_preset;
  d.sky = &sky;
  d.exposure = exposure;
  d.name = "reference";
  CloudLightingReport r = FitCloudDayKnownSky({d}, shapes, o, renderer).at(0);
  r.time_of_day_h.reset();
  return r;
}

std::vector<CloudLightingReport> FitCloudDayKnownSky(const std::vector<DayReference>& day, const KnownCloudShapes& shapes,
                                                     const CloudLightingOptions& o, clouds::CloudRenderer* renderer) {
  const auto t0 = Clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  CheckShapes(shapes);
  if (day.empty()) throw Error("cloud lighting fit: no reference");
  std::unique_ptr<clouds::CloudRenderer> cpu;
  clouds::CloudRenderer* images = renderer;
  if (!images) {
    cpu = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble, o.threads);
    images = cpu.get();
  }
  std::vector<Member> m;
  for (size_t r = 0; r < day.size(); ++r) {
    const DayReference& d = day[r];
    if (!d.reference || !d.sky || !d.sky_preset) throw Error("cloud lighting fit: a day reference without its images");
    if (d.sky->width != d.reference->width || d.sky->height != d.reference->height) {
      throw Error("cloud lighting fit: the sky image is not the reference's size");
    }
    Member x;
    x.name = d.name;
    x.time_h = d.time_of_day_h;
    x.reference = d.reference;
    x.sky_preset = *d.sky_preset;
    x.sky_exposed = Exposed(*d.sky, d.exposure);
    x.exposure = d.exposure;
    KnownCloudShapes own = shapes;
    own.time_s = shapes.TimeOf(r);
    x.request = RequestFor(d.sun_dir, d.reference->width, d.reference->height, own);
    const clouds::CloudImage start =
        images->Render({d.sky_preset, &shapes.params, shapes.noise, shapes.weather}, x.request);
    x.pixels = CloudPixelsOf(UsableAboveHorizon(*d.reference), start, o.cloud_transmittance);
    if (x.pixels.empty()) throw Error(d.name + ": the known cloud shapes cover no usable pixel of the reference");
    x.model = std::make_unique<CloudSampleModel>(
        CloudSampleScene{*d.sky_preset, shapes.params, shapes.noise, shapes.weather, x.request},
        ChooseSamples(x.pixels, *d.reference, o.samples),
        renderer && o.values_from_renderer ? CloudValueSource::kRenderer : CloudValueSource::kCpuDouble, renderer, o.threads);
    x.model->SetSky(*d.sky_preset, *d.sky, d.exposure);
    m.push_back(std::move(x));
  }
  CheckDayTimes(m);
  const CloudLighting start = GetCloudLighting(shapes.params);
  std::vector<CloudLightingReport> out =
      ReportMembers(m, start, SolveMembers(m, start, o), shapes, images, "fitted with the sky given");
  for (CloudLightingReport& r : out) {
    r.time_s = Seconds(t0);
    if (!renderer) r.value_source = "cpu double model at the samples";
  }
  return out;
}

CloudDecision DecideClouds(CloudMode mode, const std::vector<fit::Reference>& refs, const render::Preset& init,
                           bool shapes_given, double min_cloud_fraction) {
  const auto t0 = Clock::now();
  CloudDecision d;
  if (mode == CloudMode::kOff) {
    d.why = "CloudMode off: the sky alone is fitted; no cloud is marched";
    return d;
  }
  const std::string none_cloudy_ref = [&]() -> std::string {
    for (const fit::Reference& ref : refs) {
      render::RenderRequest req;
      req.sun_dir = ref.sun_dir;
      req.width = ref.radiance.width;
      req.height = ref.radiance.height;
      req.sun_disc = false;
      const ImageRGB clear = render::CreateRenderer(render::Backend::kCpu)->Render(init, req);
      const capture::CloudMask mask = capture::EstimateCloudProbability(ref.radiance, clear, ref.sun_dir, {});
      long long cloudy = 0;
      for (size_t i = 0; i < ref.pixel_class.size(); ++i) {
        if (ref.pixel_class[i] != fit::PixelClass::kSky) continue;
        ++d.sky_pixels;
        if (mask.probability[i] >= 0.5f) ++cloudy;
      }
      d.cloudy_pixels += cloudy;
      if (cloudy == 0 && mode == CloudMode::kOn) return ref.path;
    }
    return "";
  }();
  d.cloud_fraction = d.sky_pixels > 0 ? static_cast<double>(d.cloudy_pixels) / static_cast<double>(d.sky_pixels) : 0.0;
  d.time_s = Seconds(t0);
  const std::string seen = std::to_string(d.cloudy_pixels) + " of " + std::to_string(d.sky_pixels) +
                           " fitted sky pixels" + (refs.size() > 1 ? " of " + std::to_string(refs.size()) + " references" : "") +
                           " are cloud (" + FormatNumber(100.0 * d.cloud_fraction) + "%, cloud mask probability >= 0.5)";
  if (mode == CloudMode::kOn) {
    if (!none_cloudy_ref.empty()) {
      throw Error(none_cloudy_ref + ": CloudMode on but the reference has no cloud pixels (cloud mask probability >= 0.5; " +
                  seen + "): fit it with CloudMode off or auto");
    }
    if (!shapes_given) throw Error("CloudMode on needs the cloud shapes: KnownCloudShapes (a preset's clouds section)");
    d.march = true;
    d.why = "CloudMode on: " + seen;
    return d;
  }
  if (d.cloud_fraction < min_cloud_fraction) {
    d.why = "CloudMode auto: clear (" + seen + ", below " + FormatNumber(100.0 * min_cloud_fraction) +
            "%): no cloud is marched and every cloud parameter is held";
    return d;
  }
  if (!shapes_given) {
    d.why = "CloudMode auto: " + seen +
            ", but no cloud shapes were given (KnownCloudShapes): the known-shapes term cannot run; clouds off (their "
            "pixels still count in the sky terms)";
    return d;
  }
  d.march = true;
  d.why = "CloudMode auto: cloudy (" + seen + "): the cloud lighting joins the fit";
  return d;
}

namespace {

void CheckSkyAndCloudsInputs(const std::vector<fit::Reference>& refs, CloudTermKind kind,
                             const KnownCloudShapes* shapes, const CloudLightingOptions& o,
                             const clouds::CloudRenderer* cloud_renderer) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (kind != CloudTermKind::kKnownShapes) throw Error("cloud lighting fit: unknown cloud term kind");
  if (!shapes) throw Error("cloud lighting fit: the known-shapes term needs the shapes (--cloud-preset)");
  if (!cloud_renderer) throw Error("cloud lighting fit: no cloud renderer");
  if (!shapes->time_s_per_reference.empty() && shapes->time_s_per_reference.size() != refs.size()) {
    throw Error("cloud lighting fit: one wind time per reference");
  }
  CheckShapes(*shapes);
}

// The cloud pixels of every reference (the known shapes at the start's light), which
// leave the sky terms (kUserMasked) for the cloud blocks: fills each member's pixels and
// request, and returns the references with those pixels masked.
std::vector<fit::Reference> MaskCloudPixels(const std::vector<fit::Reference>& refs, const render::Preset& init,
                                            const KnownCloudShapes& shapes, const CloudLightingOptions& o,
                                            clouds::CloudRenderer* cloud_renderer, std::vector<Member>* members) {
  std::vector<Member>& m = *members;
  std::vector<fit::Reference> masked = refs;
  for (size_t r = 0; r < refs.size(); ++r) {
    const fit::Reference& ref = refs[r];
    Member& x = m[r];
    x.name = ref.name;
    x.time_h = ref.time_of_day_h;
    x.reference = &ref.radiance;
    KnownCloudShapes own = shapes;
    own.time_s = shapes.TimeOf(r);
    x.request = RequestFor(ref.sun_dir, ref.radiance.width, ref.radiance.height, own);
    // Only the transmittance is read: marched without the light samples, which feed the
    // source term alone (cloud_march.glsl.h), it is the same to the bit and cheaper (the
    // primary march's density reads remain).
    clouds::CloudRenderRequest opacity_only = x.request;
    opacity_only.march.light_samples = 0;
    opacity_only.march.far_light = false;
    const clouds::CloudImage start_image =
        cloud_renderer->Render({&init, &shapes.params, shapes.noise, shapes.weather}, opacity_only);
    std::vector<char> usable(ref.pixel_class.size());
    for (size_t i = 0; i < usable.size(); ++i) usable[i] = ref.pixel_class[i] == fit::PixelClass::kSky ? 1 : 0;
    x.pixels = CloudPixelsOf(usable, start_image, o.cloud_transmittance);
    if (x.pixels.empty()) {
      throw Error(ref.path + ": --clouds: the known cloud shapes (--cloud-preset, --cloud-time) cover none of the "
                  "reference's fitted sky pixels (transmittance < " + FormatNumber(o.cloud_transmittance) + ")");
    }
    for (size_t i : x.pixels) masked[r].pixel_class[i] = fit::PixelClass::kUserMasked;
    masked[r].counts.sky -= static_cast<long long>(x.pixels.size());
    masked[r].counts.user_masked += static_cast<long long>(x.pixels.size());
  }
  return masked;
}

// The sky stage's pixels given by the caller (their classes and counts), per reference.
void UseSkyPixelClasses(const std::vector<std::vector<fit::PixelClass>>& classes, std::vector<fit::Reference>* refs) {
  if (classes.size() != refs->size()) throw Error("FitSkyAndClouds: sky_pixel_class has " + std::to_string(classes.size()) +
                                                  " references' classes for " + std::to_string(refs->size()) + " references");
  for (size_t r = 0; r < refs->size(); ++r) {
    fit::Reference& ref = (*refs)[r];
    if (classes[r].size() != ref.pixel_class.size()) throw Error(ref.path + ": sky_pixel_class is not the frame's size");
    ref.pixel_class = classes[r];
    ref.counts = fit::CountPixelClasses(ref.pixel_class);
  }
}

// The cloud blocks on the fitted sky (after its gauge move), values through the renderer.
// Member x's sample model on `shapes` over its sky (x.sky, x.sky_preset, x.exposure).
void MakeCloudModel(const fit::Reference& ref, const KnownCloudShapes& shapes, const CloudLightingOptions& o,
                    clouds::CloudRenderer* cloud_renderer, Member* x) {
  x->model = std::make_unique<CloudSampleModel>(
      CloudSampleScene{x->sky_preset, shapes.params, shapes.noise, shapes.weather, x->request},
      ChooseSamples(x->pixels, ref.radiance, o.samples),
      o.values_from_renderer ? CloudValueSource::kRenderer : CloudValueSource::kCpuDouble, cloud_renderer, o.threads);
  x->model->SetSky(x->sky_preset, x->sky, x->exposure);
}

void BuildCloudModels(const std::vector<fit::Reference>& refs, const fit::FitResult& sky_fit,
                      const KnownCloudShapes& shapes, const CloudLightingOptions& o,
                      clouds::CloudRenderer* cloud_renderer, std::vector<Member>* members) {
  std::vector<Member>& m = *members;
  const std::unique_ptr<render::SkyRenderer> cpu_sky = render::CreateRenderer(render::Backend::kCpu);
  for (size_t r = 0; r < refs.size(); ++r) {
    Member& x = m[r];
    render::RenderRequest req;
    req.sun_dir = refs[r].sun_dir;
    req.width = refs[r].radiance.width;
    req.height = refs[r].radiance.height;
    req.sun_disc = false;  // the sun cone is masked; the clouds' sun light is the direct term
    x.sky = cpu_sky->Render(sky_fit.preset, req);
    x.sky_preset = sky_fit.preset;
    x.exposure = sky_fit.references[r].exposure;
    // The report's composites over the rendered sky (the backend's, disc included).
    x.sky_exposed = sky_fit.references[r].rendered;
    MakeCloudModel(refs[r], shapes, o, cloud_renderer, &x);
  }
}

// The solve, and with CloudLightingOptions::refine_shapes (one reference) the map refined with
// the lighting found and the lighting solved on from there on it (no holds released; the sky
// and the cloud pixels kept): the report's composites are then drawn once, on the final map.
Solved SolveAndRefine(const std::vector<fit::Reference>& refs, const CloudLighting& start,
                      const CloudLightingOptions& o, clouds::CloudRenderer* cloud_renderer, KnownCloudShapes* shapes,
                      std::vector<Member>* m, std::optional<clouds::WeatherMap>* refined) {
  Solved first = SolveMembers(*m, start, o);
  if (!o.refine_shapes || m->size() != 1) return first;
  clouds::CloudParams lit = shapes->params;
  SetCloudLighting(first.theta[0], &lit);
  *refined = o.refine_shapes->Refine((*m)[0].sky_preset, lit, (*m)[0].exposure, *shapes->weather);
  if (!*refined) return first;
  const CloudSampleModel& before = *(*m)[0].model;  // its counts and times, carried over
  const int renders = before.renders, jacobians = before.jacobians;
  const double render_s = before.render_time_s, jacobian_s = before.jacobian_time_s;
  shapes->weather = &**refined;
  MakeCloudModel(refs[0], *shapes, o, cloud_renderer, &(*m)[0]);  // the same sky and samples
  CloudSampleModel& after = *(*m)[0].model;
  after.renders += renders;
  after.jacobians += jacobians;
  after.render_time_s += render_s;
  after.jacobian_time_s += jacobian_s;
  CloudLightingOptions on = o;
  on.max_iterations = o.iterations_after_refinement;
  on.restart_at_bounds = on.release_inseparable = false;
  on.refine_shapes = nullptr;
  Solved second = SolveMembers(*m, first.theta[0], on);
  second.again = first.again;  // what the first solve's restarts and releases did
  second.iterations += first.iterations;
  second.conditioning_s += first.conditioning_s;
  second.solve_s += first.solve_s;
  return second;
}

// The outputs: each reference's composite with its fitted clouds over the fitted sky, and
// the sky stages' times and renders (from the fit's report, out->clouds) in each cloud
// report.
void ComposeOutputs(const std::vector<fit::Reference>& refs, const std::vector<Member>& m,
                    const KnownCloudShapes& shapes, const CloudDecision& decision,
                    clouds::CloudRenderer* cloud_renderer, SkyCloudFit* out) {
  const double cloud_pixels_s = out->clouds.cloud_pixels_time_s, sky_fit_s = out->clouds.sky_fit_time_s;
  const int sky_renders = out->clouds.sky_renders;
  for (size_t r = 0; r < refs.size(); ++r) {
    CloudLightingReport& cr = out->references[r];
    fit::ReferenceFit& rf = out->sky.references[r];
    const clouds::CloudImage* fitted = m[r].model->RenderedAt(GetCloudLighting(cr.fitted_params).data());
    const clouds::CloudImage image =
        fitted ? *fitted
               : cloud_renderer->Render({&out->sky.preset, &cr.fitted_params, shapes.noise, shapes.weather}, m[r].request);
    rf.rendered = Composite(m[r].sky_exposed, image, rf.exposure);
    cr.clear.pixels = rf.errors.pixels;
    cr.clear.rel_rmse = rf.errors.rel_rmse;
    cr.clear.log_rmse = rf.errors.log_rmse;
    rf.errors = fit::CompareToReference(refs[r], rf.rendered);  // the whole sky, cloud pixels included
    cr.cloud_fraction = decision.cloud_fraction;
    cr.cloud_pixels_time_s = cloud_pixels_s;
    cr.sky_fit_time_s = sky_fit_s;
    cr.sky_renders = sky_renders;
  }
}

// The fit's report: the earliest reference's (a day: its values head the day's keys),
// with the whole solve's counts and the time of every stage.
void SummariseClouds(const std::vector<Member>& m, const CloudLightingOptions& o, Clock::time_point t0,
                     SkyCloudFit* out) {
  CloudLightingReport& rep = out->clouds;
  size_t first = 0;
  for (size_t r = 1; r < m.size(); ++r) {
    if (m[r].time_h && m[first].time_h && *m[r].time_h < *m[first].time_h) first = r;
  }
  rep = out->references[first];
  rep.renders = rep.jacobians = 0;
  rep.render_time_s = rep.jacobian_time_s = 0.0;
  long long pixels = 0;
  for (const CloudLightingReport& cr : out->references) {
    rep.renders += cr.renders;
    rep.jacobians += cr.jacobians;
    rep.render_time_s += cr.render_time_s;
    rep.jacobian_time_s += cr.jacobian_time_s;
    pixels += cr.cloud_pixels;
  }
  rep.time_s = Seconds(t0);
  out->sky.time_s = rep.time_s;  // fit.json time_s: the whole fit, sky and clouds
  out->sky.decisions.push_back(
      {"sky terms without the cloud pixels",
       std::to_string(pixels) + " pixels whose known-shape transmittance is below " + FormatNumber(o.cloud_transmittance) +
           " are fitted by the cloud blocks (sky x T + clouds), not the sky rows; the sky is fitted first on its clear "
           "pixels (its linear stage, as a clear sky), then the cloud blocks on it",
       0.0, "measured: the sky fit's part of the whole fit is clouds.solve.sky_fit_time_s", std::nullopt, ""});
}

}  // namespace

SkyCloudFit FitSkyAndClouds(const std::vector<fit::Reference>& refs, const render::Preset& init,
                            const fit::FitOptions& fo, render::SkyRenderer& renderer,
                            const std::vector<const fit::ProbeSamples*>& probes, const CloudDecision& decision,
                            CloudTermKind kind, const KnownCloudShapes* shapes, const CloudLightingOptions& o,
                            clouds::CloudRenderer* cloud_renderer,
                            const std::vector<std::vector<fit::PixelClass>>* sky_pixel_class) {
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
  CheckSkyAndCloudsInputs(refs, kind, shapes, o, cloud_renderer);
  std::vector<Member> m(refs.size());
  std::vector<fit::Reference> masked = MaskCloudPixels(refs, init, *shapes, o, cloud_renderer, &m);
  if (sky_pixel_class) UseSkyPixelClasses(*sky_pixel_class, &masked);
  CheckDayTimes(m);
  rep.cloud_pixels_time_s = Seconds(t0);

  // The sky on its clear pixels: a clear-sky fit (the linear stage; Ceres only where the
  // sky alone needs it: probes, --polish, a failed render check).
  const auto ts = Clock::now();
  out.sky = fit::FitSky(masked, init, fo, renderer, probes);
  rep.sky_fit_time_s = Seconds(ts);
  for (const fit::LevelReport& l : out.sky.levels) rep.sky_renders += l.renders;

  BuildCloudModels(refs, out.sky, *shapes, o, cloud_renderer, &m);
  KnownCloudShapes used = *shapes;  // the refined map's, when refined
  const Solved solved = SolveAndRefine(refs, start, o, cloud_renderer, &used, &m, &out.refined_weather);
  out.references = ReportMembers(m, start, solved, used, cloud_renderer, decision.why);
  ComposeOutputs(refs, m, used, decision, cloud_renderer, &out);
  SummariseClouds(m, o, t0, &out);
  return out;
}

}  // namespace skycal::cloudfit
