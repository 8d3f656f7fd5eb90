// Suite `stress`: numerical stability across the pipeline (docs/benchmarks.md). Each case feeds one
// hostile or extreme input and checks every output number is finite; a clear skycal::Error
// is a pass (the tool refused and said why), a non-finite output or another exception is a
// failure. Fits also record convergence. Areas:
//   render   sun -18..90 deg incl. exactly 0 and 90 and +-1e-7 around the horizon, x g
//            0..0.999, both backends; every LUT entry scaled to 1e-8 and 1e8.
//   fit      random starts (bench_fit_stress's study: tables x10^U(-1,1), g U(0,0.95),
//            exposure x10^U(-3,3)); references with NaN/Inf/negative islands, a clipped
//            plateau, one valid row.
//   capture  all-clipped and all-black brackets, identical exposure times, one usable bracket.
//   probe    a ball at and over the image edge, one sample, all clipped, NaN in the ball.
//   export   LUTs scaled 1e-8 / 1e8 / both together at several headrooms: half-float
//            overflow (a clear error) and underflow counts.
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <random>

#include "cloud_scene.h"
#include "skycal/export/game_export.h"
#include "fisheye_brackets.h"
#include "image_compare.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/controllers/probe_extract.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/png_io.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

using Clock = std::chrono::steady_clock;

// Every number in a JSON value is finite (nlohmann keeps NaN/Inf as doubles in memory).
bool JsonFinite(const nlohmann::json& j) {
  if (j.is_number_float()) return std::isfinite(j.get<double>());
  if (j.is_structured())
    for (const auto& v : j)
      if (!JsonFinite(v)) return false;
  return true;
}

bool PresetFinite(const render::Preset& p) {
  for (const auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic})
    for (float v : *t)
      if (!std::isfinite(v)) return false;
  return std::isfinite(p.haziness_g) && std::isfinite(p.overcast_zenith_cd_m2);
}

void ScaleLuts(render::Preset& p, double k) {
  for (auto* t : {&p.luts.rayleigh, &p.luts.mie, &p.luts.isotropic})
    for (float& v : *t) v = static_cast<float>(v * k);
}

void NonFinite(CaseResult& c, const std::string& what) {
  c.outcome = Outcome::kNonFinite;
  c.message = what;
}

// A stress case runs once; its wall time is recorded for the table (no repeats).
struct Runner {
  const SuiteOptions& o;
  std::vector<CaseResult> out;
  int k = 0;
  void operator()(const std::string& area, const std::string& input, const std::function<void(CaseResult&)>& body) {
    auto result = RunCase("stress", {{"area", area}, {"input", input}}, {}, k++, -1, o, [&](CaseResult& c) {
      c.timed = false;
      const auto t0 = Clock::now();
      auto stamp = [&] { c.time = FromSamples({std::chrono::duration<double, std::milli>(Clock::now() - t0).count()}); };
      try {
        body(c);
      } catch (...) {
        stamp();  // a refusal's time too: it should be quick
        throw;
      }
      stamp();
    });
    if (result) out.push_back(std::move(*result));
  }
};

std::string Num(double v) { return FormatG(v, 8); }

void RenderArea(Runner& run, const SuiteOptions& o) {
  const render::Preset base = render::LoadPreset(DefaultPresetPath());
  std::unique_ptr<render::SkyRenderer> backends[2] = {render::CreateRenderer(render::Backend::kCpu),
                                                      render::CreateRenderer(render::Backend::kVulkan)};
  const int width = o.quick ? 64 : 256;
  auto render_case = [&](render::SkyRenderer& r, const render::Preset& p, double el, CaseResult& c) {
    render::RenderRequest req;
    req.width = width;
    req.height = width / 2;
    req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(el, 20.0);
    const ImageRGB im = r.Render(p, req);
    if (!AllFinite(im)) NonFinite(c, "non-finite radiance");
    double max_v = 0.0;
    for (float v : im.pixels) max_v = std::max(max_v, static_cast<double>(v));
    c.extra = {{"max_radiance", max_v}};
  };
  for (auto& r : backends) {
    const std::string be = r->Describe().rfind("vulkan", 0) == 0 ? "vulkan" : "cpu";
    for (double el : {-18.0, -10.0, -1.0, -1e-7, 0.0, 1e-7, 1.0, 10.0, 45.0, 90.0 - 1e-7, 90.0})
      for (double g : {0.0, 0.5, 0.9, 0.999}) {
        run("render", be + " sun " + Num(el) + " g " + Num(g), [&](CaseResult& c) {
          render::Preset p = base;
          p.haziness_g = g;
          render_case(*r, p, el, c);
        });
      }
    for (double k : {1e-8, 1e8})
      for (double el : {0.0, 45.0})
        run("render", be + " LUT x" + Num(k) + " sun " + Num(el), [&](CaseResult& c) {
          render::Preset p = base;
          ScaleLuts(p, k);
          render_case(*r, p, el, c);
        });
  }
}

// Clouds: extreme densities (extinction per unit density up to the spec's bound, then
// beyond it: a refusal naming the field is a pass), step counts 1...2,048, no and many
// light samples, the sun around the horizon and at the zenith; both backends. Checked:
// radiance finite and >= 0, transmittance finite and in [0, 1].
void CloudsArea(Runner& run, const SuiteOptions& o) {
  const CloudBenchScene scene = LoadDefaultCloudyScene();
  std::unique_ptr<clouds::CloudRenderer> backends[2] = {clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble),
                                                        clouds::CreateVulkanCloudRenderer()};
  const int width = o.quick ? 32 : 64;
  auto cloud_case = [&](clouds::CloudRenderer& r, const clouds::CloudParams& params, const clouds::MarchOptions& m,
                        double el, CaseResult& c) {
    clouds::CloudRenderRequest req;
    req.width = width;
    req.height = width / 2;
    req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(el, 40.0);
    req.march = m;
    const clouds::CloudScene view{&scene.preset, &params, &scene.noise, &scene.weather};
    const clouds::CloudImage im = r.Render(view, req);
    if (!AllFinite(im.radiance)) return NonFinite(c, "non-finite cloud radiance");
    float min_l = 0.0f, min_t = 1.0f, max_t = 0.0f;
    for (float v : im.radiance.pixels) min_l = std::min(min_l, v);
    for (float t : im.transmittance) {
      if (!std::isfinite(t)) return NonFinite(c, "non-finite transmittance");
      min_t = std::min(min_t, t);
      max_t = std::max(max_t, t);
    }
    if (min_l < 0.0f) return NonFinite(c, "negative cloud radiance " + Num(min_l));
    if (min_t < 0.0f || max_t > 1.0f) return NonFinite(c, "transmittance outside [0, 1]: " + Num(min_t) + " .. " + Num(max_t));
    c.extra = {{"min_transmittance", min_t}};
  };
  for (auto& r : backends) {
    const std::string be = r->Describe().rfind("vulkan", 0) == 0 ? "vulkan" : "cpu";
    for (double ext : {0.0, 1e-9, 0.05, 1.0, 1e3})
      for (double coverage : {0.0, 1.0, 2.0}) {
        run("clouds", be + " extinction " + Num(ext) + "/m coverage x" + Num(coverage), [&](CaseResult& c) {
          clouds::CloudParams p = scene.params;
          p.extinction_per_m = ext;
          p.coverage_scale = coverage;
          clouds::ValidateCloudParams(p, "stress");  // 1e3 /m is out of bounds: a clear refusal
          cloud_case(*r, p, clouds::MarchOptions{}, 25.0, c);
        });
      }
    for (int steps : {1, 2, 2048})
      for (int light : {0, 1, 64}) {
        if (o.quick && steps == 2048 && light == 64) continue;  // the CI size stays in seconds
        run("clouds", be + " steps " + std::to_string(steps) + " light " + std::to_string(light), [&](CaseResult& c) {
          clouds::MarchOptions m;
          m.steps_zenith = m.steps_horizon = steps;
          m.light_samples = light;
          std::string why;
          if (!m.IsValid(&why)) throw Error(why);
          cloud_case(*r, scene.params, m, 25.0, c);
        });
      }
    for (double el : {-18.0, -1e-7, 0.0, 1e-7, 90.0})
      run("clouds", be + " sun " + Num(el), [&](CaseResult& c) { cloud_case(*r, scene.params, clouds::MarchOptions{}, el, c); });
  }
}

// A reference sky of the fit area and the default start's error on it clean.
struct StressSky {
  std::string name, path;
  double clean_error = 0.0;
};

// Two skies (four without --quick): CIE and baked atmospheres, written at kWidth. The
// default start's error on each clean sky: "converged" means within 1.2x of it + 0.1%
// (bench_fit_stress used the model's ceiling; this is cheaper and no looser in practice).
std::vector<StressSky> StressSkies(const SuiteOptions& o, const fit::FitOptions& fo, const render::Preset& preset,
                                   render::SkyRenderer& vulkan) {
  constexpr int kWidth = 256;
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  const auto variants = refsky::StandardAtmosphereVariants();
  std::vector<StressSky> skies = {{"CIE 7 sun 45", (o.scratch / "stress_cie7.exr").string()},
                                  {"bake 0 sun 10", (o.scratch / "stress_bake0.exr").string()}};
  refsky::WriteCieReference(skies[0].path, types[6], latlong::DirectionFromElevationAzimuthDeg(45.0, 30.0), kWidth);
  refsky::WriteModelReference(skies[1].path, refsky::BakeVariant(variants[0]), latlong::DirectionFromElevationAzimuthDeg(10.0, -70.0), kWidth);
  if (!o.quick) {
    skies.push_back({"CIE 13 sun 10", (o.scratch / "stress_cie13.exr").string()});
    refsky::WriteCieReference(skies[2].path, types[12], latlong::DirectionFromElevationAzimuthDeg(10.0, 30.0), kWidth);
    skies.push_back({"bake 1 sun -3", (o.scratch / "stress_bake1.exr").string()});
    refsky::WriteModelReference(skies[3].path, refsky::BakeVariant(variants[1]), latlong::DirectionFromElevationAzimuthDeg(-3.0, -70.0), kWidth);
  }
  for (StressSky& s : skies) s.clean_error = fit::FitSky({fit::LoadReference(s.path, fo)}, preset, fo, vulkan).references[0].errors.rel_rmse;
  return skies;
}

// A fit's result checked: finite preset, error and exposure; converged when within 1.2x
// of tolerance_error + 0.1% (tolerance_error < 0: no convergence expected).
void CheckStressFit(CaseResult& c, const fit::FitResult& r, double tolerance_error) {
  const double err = r.references.at(0).errors.rel_rmse;
  const bool finite = PresetFinite(r.preset) && std::isfinite(err) && std::isfinite(r.references[0].exposure);
  if (!finite) NonFinite(c, "non-finite preset, error or exposure");
  c.error = err;
  if (tolerance_error >= 0.0) c.converged = finite && err <= 1.2 * tolerance_error + 1e-3;
}

// Random starts: the LUTs scaled by 0.1..10 each, any g, the reference's exposure 1e-3..1e3.
void RandomStartCases(Runner& run, const SuiteOptions& o, const std::vector<StressSky>& skies,
                      const render::Preset& preset, const fit::FitOptions& fo, render::SkyRenderer& vulkan) {
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int starts = o.quick ? 4 : 20;
  for (const StressSky& sky : skies) {
    const fit::Reference clean = fit::LoadReference(sky.path, fo);
    for (int k = 0; k < starts; ++k) {
      render::Preset start = preset;
      double scales[3];
      for (double& s : scales) s = std::pow(10.0, -1.0 + 2.0 * u(rng));
      int t = 0;
      for (auto* table : {&start.luts.rayleigh, &start.luts.mie, &start.luts.isotropic}) {
        for (float& v : *table) v = static_cast<float>(v * scales[t]);
        ++t;
      }
      start.haziness_g = 0.95 * u(rng);
      const double exposure = std::pow(10.0, -3.0 + 6.0 * u(rng));
      run("fit", sky.name + " random start " + std::to_string(k), [&](CaseResult& c) {
        fit::Reference ref = clean;
        for (float& v : ref.radiance.pixels) v = static_cast<float>(v * exposure);
        ref.clip_level *= exposure;
        c.extra = {{"table_scales", {scales[0], scales[1], scales[2]}}, {"g", start.haziness_g}, {"exposure", exposure}};
        CheckStressFit(c, fit::FitSky({ref}, start, fo, vulkan), sky.clean_error);
      });
    }
  }
}

// Damaged references (the first sky): written as frames, loaded as a user's would be.
void DamagedReferenceCases(Runner& run, const SuiteOptions& o, const StressSky& sky, const render::Preset& preset,
                           const fit::FitOptions& fo, render::SkyRenderer& vulkan) {
  const capture::LatLongFrame frame = capture::ReadLatLongFrame(sky.path);
  struct Damage {
    std::string name;
    std::function<void(ImageRGB&)> apply;
    bool expect_convergence;
  };
  const float nan = std::nanf(""), inf = INFINITY;
  auto island = [](ImageRGB& im, float v) {
    for (int y = im.height / 8; y < im.height / 4; ++y)
      for (int x = im.width / 4; x < im.width / 3; ++x)
        for (int c = 0; c < 3; ++c) im.at(x, y, c) = v;
  };
  const std::vector<Damage> damages = {
      {"NaN island", [&](ImageRGB& im) { island(im, nan); }, true},
      {"+Inf island", [&](ImageRGB& im) { island(im, inf); }, true},
      {"negative island", [&](ImageRGB& im) { island(im, -100.0f); }, true},
      {"clipped plateau (top 20% of values)",
       [](ImageRGB& im) {
         std::vector<float> v(im.pixels);
         std::nth_element(v.begin(), v.begin() + v.size() * 8 / 10, v.end());
         const float clip = v[v.size() * 8 / 10];
         for (float& p : im.pixels) p = std::min(p, clip);
       },
       false},
      {"one valid row",
       [&](ImageRGB& im) {
         for (int y = 0; y < im.height; ++y)
           if (y != im.height / 4)
             for (int x = 0; x < im.width; ++x)
               for (int c = 0; c < 3; ++c) im.at(x, y, c) = nan;
       },
       false},
      {"all NaN", [&](ImageRGB& im) { for (float& p : im.pixels) p = nan; }, false},
      {"all zero", [&](ImageRGB& im) { for (float& p : im.pixels) p = 0.0f; }, false},
  };
  int n = 0;
  for (const Damage& d : damages) {
    run("fit", sky.name + " " + d.name, [&](CaseResult& c) {
      capture::LatLongFrame f = frame;
      d.apply(f.radiance);
      const std::string path = (o.scratch / ("stress_damaged_" + std::to_string(n++) + ".exr")).string();
      capture::WriteLatLongFrame(path, f);
      CheckStressFit(c, fit::FitSky({fit::LoadReference(path, fo)}, preset, fo, vulkan), d.expect_convergence ? sky.clean_error : -1.0);
    });
  }
}

void FitArea(Runner& run, const SuiteOptions& o) {
  fit::FitOptions fo;
  fo.verbose = false;
  const render::Preset preset = render::LoadPreset(DefaultPresetPath());
  auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
  const std::vector<StressSky> skies = StressSkies(o, fo, preset, *vulkan);
  RandomStartCases(run, o, skies, preset, fo, *vulkan);
  DamagedReferenceCases(run, o, skies[0], preset, fo, *vulkan);
}

void CaptureArea(Runner& run, const SuiteOptions& o) {
  constexpr int kFisheye = 256;
  const std::string dir = (o.scratch / "stress_capture").string();
  std::filesystem::create_directories(dir);
  const FisheyeBrackets b = WriteFisheyeBrackets(256, kFisheye, dir);
  const std::vector<std::string>& good = b.paths;
  auto constant = [&](const std::string& name, int value) {
    const std::string p = dir + "/" + name + ".png";
    Raster grey(kFisheye, kFisheye, 3, 8);
    std::fill(grey.data.begin(), grey.data.end(), static_cast<uint8_t>(value));
    const std::vector<uint8_t> png = EncodePng(grey, p);
    WriteFileAtomically(p, std::string(png.begin(), png.end()));
    return p;
  };
  const std::string white = constant("white", 255), black = constant("black", 0);
  struct Input {
    std::string name;
    std::vector<std::string> brackets;
    std::vector<double> times;
  };
  const std::vector<double>& t = b.exposure_times_s;
  std::vector<Input> inputs = {
      {"all clipped", std::vector<std::string>(t.size(), white), t},
      {"all black", std::vector<std::string>(t.size(), black), t},
      {"identical exposure times", good, std::vector<double>(t.size(), t[3])},
      {"one usable bracket (others clipped)", {good[0], white, white}, {t[0], t[1], t[2]}},
      {"one usable bracket (others black)", {black, black, good[6]}, {t[4], t[5], t[6]}},
      {"two brackets", {good[2], good[4]}, {t[2], t[4]}},
  };
  int n = 0;
  for (const Input& in : inputs)
    for (const char* response : {"debevec", "srgb"}) {
      run("capture", in.name + " " + response, [&](CaseResult& c) {
        capture::CaptureOptions co =
            FisheyeCaptureOptions(in.brackets, in.times, response, 128, dir + "/frame_" + std::to_string(n++) + ".exr");
        co.verbose = o.verb_logs;
        const nlohmann::json summary = capture::RunCapturePipeline(co);
        const ImageRGB frame = capture::ReadLatLongFrame(co.out).radiance;
        if (!AllFinite(frame)) NonFinite(c, "non-finite radiance in the frame");
        else if (!JsonFinite(summary)) NonFinite(c, "non-finite number in the summary");
        c.extra = {{"valid_pixels", summary.value("valid_pixels", 0LL)}};
      });
    }
}

void ProbeArea(Runner& run, const SuiteOptions& o) {
  // A 256x256 linear EXR with a Lambertian ball (radius 60 px at the centre) lit from above.
  constexpr int kSize = 256;
  auto ball_image = [&](double cx, double cy, double r, float nan_value) {
    ImageRGB im(kSize, kSize);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const double dx = (x - cx) / r, dy = (y - cy) / r, d2 = dx * dx + dy * dy;
        float v = 0.05f;
        if (d2 < 1.0) v = static_cast<float>(0.2 + 0.8 * std::max(0.0, -dy));
        if (d2 < 0.04 && nan_value != 0.0f) v = nan_value;  // 0: no damage
        for (int c = 0; c < 3; ++c) im.at(x, y, c) = v;
      }
    return im;
  };
  struct Input {
    std::string name;
    double cx, cy, r;
    float centre;
    double clip;
  };
  const std::vector<Input> inputs = {
      {"ball centred (baseline)", 128, 128, 60, 0.0f, INFINITY},
      {"ball touching the edge", 60, 128, 60, 0.0f, INFINITY},
      {"ball half outside", 10, 128, 60, 0.0f, INFINITY},
      {"ball 1 px: one sample", 128, 128, 1.0, 0.0f, INFINITY},
      {"ball all clipped", 128, 128, 60, 0.0f, 0.01},
      {"NaN at the ball's centre", 128, 128, 60, std::nanf(""), INFINITY},
      {"Inf at the ball's centre", 128, 128, 60, INFINITY, INFINITY},
  };
  int n = 0;
  for (const Input& in : inputs) {
    run("probe", in.name, [&](CaseResult& c) {
      const std::string path = (o.scratch / ("stress_ball_" + std::to_string(n) + ".exr")).string();
      WriteExrRGB(path, ball_image(in.cx, in.cy, in.r, in.centre), {});
      controllers::ProbeExtractOptions po;
      po.image = path;
      po.circle = capture::BallCircle{in.cx, in.cy, in.r};
      po.clip_level = in.clip;
      po.verbose = o.verb_logs;
      po.out = (o.scratch / ("stress_ball_" + std::to_string(n++) + ".json")).string();
      const nlohmann::json summary = controllers::ExtractProbe(po);
      if (!JsonFinite(summary)) NonFinite(c, "non-finite number in the samples");
      if (summary.contains("samples") && summary["samples"].is_array()) c.extra = {{"samples", summary["samples"].size()}};
    });
  }
}

void ExportArea(Runner& run, const SuiteOptions& o) {
  const render::Preset base = render::LoadPreset(DefaultPresetPath());
  auto write = [&](const std::string& name, double k) {
    render::Preset p = base;
    p.name = name;
    ScaleLuts(p, k);
    const std::string path = (o.scratch / ("stress_" + name + ".json")).string();
    render::SavePreset(p, path);
    return path;
  };
  const std::string tiny = write("lut_x1e-8", 1e-8), huge = write("lut_x1e8", 1e8), plain = DefaultPresetPath();
  struct Input {
    std::string name;
    std::vector<std::string> presets;
  };
  const std::vector<Input> inputs = {{"LUT x1e-8", {tiny}}, {"LUT x1e8", {huge}}, {"LUT x1e-8 with x1e8", {tiny, huge}},
                                     {"bundled with x1e8", {plain, huge}}};
  int n = 0;
  for (const Input& in : inputs)
    // 1 - 2^-12: the largest texel lands within half an FP16 ulp of 65504, the format's
    // maximum (the pre-exposure's rounding must not carry it past, to infinity).
    for (double headroom : {1e-6, 0.25, 1.0 - 1.0 / 4096.0, 1.0}) {
      run("export", in.name + " headroom " + Num(headroom), [&](CaseResult& c) {
        exporter::ExportOptions eo;
        eo.presets = in.presets;
        eo.headroom = headroom;
        eo.backend = render::Backend::kCpu;
        eo.report = false;  // the export's numbers are stressed, not the HTML report
        eo.verbose = o.verb_logs;
        eo.out_dir = (o.scratch / ("stress_export_" + std::to_string(n++))).string();
        const nlohmann::json summary = exporter::ExportGameTables(eo);
        if (!JsonFinite(summary)) NonFinite(c, "non-finite number in the manifest");
        long long nonfinite = 0;
        double largest = 0.0;
        for (const auto& p : summary.at("presets"))
          for (const char* t : {"rayleigh", "mie"}) {
            const ImageRGB im = ReadExrRGB(eo.out_dir + "/" + p.at("name").get<std::string>() + "/" + t + ".exr").image;
            for (float v : im.pixels) {
              nonfinite += !std::isfinite(v);
              if (std::isfinite(v)) largest = std::max(largest, static_cast<double>(v));
            }
          }
        if (nonfinite) NonFinite(c, std::to_string(nonfinite) + " half texels non-finite");
        // The pre-exposure puts the largest texel at headroom x 65504: more is a rounding
        // past the target (at headroom 1, one step more is infinity).
        constexpr double kHalfMax = 65504.0;
        if (largest > headroom * kHalfMax * (1.0 + 1.0 / 2048.0))
          NonFinite(c, "largest half texel " + Num(largest) + " above the target " + Num(headroom * kHalfMax));
        c.extra = {{"pre_exposure", summary.value("pre_exposure", 0.0)},
                   {"half_underflow_texels", summary.value("half_underflow_texels", 0LL)},
                   {"half_nonfinite_texels", nonfinite},
                   {"largest_half_texel", largest}};
      });
    }
}

}  // namespace

Suite StressSuite() {
  Suite s;
  s.name = "stress";
  s.summary = "numerical stability: extreme and hostile inputs across render, clouds, fit, capture, probe, export";
  s.error_metric = "fit: rel RMSE (other areas: none); the table counts outcomes";
  s.pareto = false;
  s.run = [](const SuiteOptions& o) {
    Runner run{o, {}, 0};
    RenderArea(run, o);
    CloudsArea(run, o);
    FitArea(run, o);
    CaptureArea(run, o);
    ProbeArea(run, o);
    ExportArea(run, o);
    return run.out;
  };
  return s;
}

}  // namespace skycal::bench
