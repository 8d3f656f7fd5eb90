// The cloud scene the clouds and stress suites render (private to skycal_bench): the
// bundled default_cloudy preset with its clouds section and weather map, noise seed 1.
#pragma once
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/core/image.h"
#include "skycal/render/preset.h"

namespace skycal::bench {
struct SuiteOptions;
struct CaseResult;
}

namespace skycal::bench {

struct CloudBenchScene {
  render::Preset preset;
  clouds::CloudParams params;
  clouds::CloudNoise noise;
  clouds::WeatherMap weather;
  clouds::CloudScene View() const { return {&preset, &params, &noise, &weather}; }
};

// Throws skycal::Error when the bundled preset or its weather map is unreadable.
CloudBenchScene LoadDefaultCloudyScene();  // clouds_suite.cc

// The march of a `march` axis value (clouds_suite.cc): "game" (the defaults), "naive"
// (every optimisation off), "no-X" (the game's with optimisation X off: cheap-march,
// step-back, return-to-cheap, opacity-stop, cheap-light, far-light) or "naive+X" (the naive
// march with X on: cheap-march (with the game's step back and return to cheap),
// cheap-march-no-step-back, opacity-stop, cheap-light, far-light). Throws skycal::Error on
// another name.
clouds::MarchOptions CloudMarchVariant(const std::string& name);

// The clouds suites' converged reference at error_req's size and sun (clouds_suite.cc):
// the double CPU march with every optimisation off, 1,024 primary steps at every elevation,
// the light integral on the sun ray (64 samples over 8 km, no cone, no far sample; 256 and
// 16 with o.quick), composited over the clear sky without the sun disc.
struct ConvergedCloudReference {
  ImageRGB sky;                // clear sky, no disc
  clouds::CloudImage clouds;   // the converged march
  ImageRGB truth;              // sky x T + clouds
};
ConvergedCloudReference MakeConvergedCloudReference(const CloudBenchScene& scene, const clouds::CloudRenderRequest& error_req,
                                                    const SuiteOptions& o);

// The composite's error against ref.truth at the same size, per pixel as RelRmse weighs it
// (solid angle, three channels, pixels above the horizon with positive finite values), split
// into c.extra (clouds_error_suite.cc): e2_elev_{0_5,5_15,15_45,45_90} by elevation (deg) and
// e2_{clear,thin,medium,thick} by the reference's T (>= 0.99, 0.7-0.99, 0.1-0.7, < 0.1), each
// the part's squared error in %^2 (each split sums to (100 RelRmse)^2);
// rel_rmse_cloud_pixels and mean_rel_error_cloud_pixels over the pixels with T < 0.99.
void CloudErrorParts(const ConvergedCloudReference& ref, const ImageRGB& composite, CaseResult& c);

// CPU time of this process so far (all threads, lavapipe's included), ms.
double ProcessCpuMs();

// The clouds suites' view: sun at 25 deg elevation, 40 deg azimuth; width x width/2 pixels.
clouds::CloudRenderRequest CloudSuiteRequest(int width);

// Times `repeats` renders of `request` after o.warmup untimed ones into c.time (wall), and
// their median process CPU time per render into c.extra["cpu_time_ms"]: on a machine shared
// with other jobs the CPU time measures the work, the wall time the share of the cores.
void TimeCloudRender(clouds::CloudRenderer& renderer, const CloudBenchScene& scene, const clouds::CloudRenderRequest& request,
                     const SuiteOptions& o, int repeats, CaseResult& c);

}  // namespace skycal::bench
