// Suite `probe`: the gray probe's irradiance at 256 Fibonacci normals from the sky of the
// bundled preset (sun 35 deg, no disc; the sun term is analytic and not part of this):
// direct quadrature of a lat-long of width W vs SH-9 projected from it. Time: the Vulkan
// render at W plus the irradiance; error: RMS relative error over the normals against
// quadrature of a CPU render at 1024 wide (512 with --quick), the converged reference.
#include <cmath>
#include <memory>

#include "skycal/core/latlong.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

double RmsRel(const std::vector<render::Rgb>& ref, const std::vector<render::Rgb>& got) {
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < ref.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      if (!(ref[i][c] > 0.0)) continue;
      const double r = (got[i][c] - ref[i][c]) / ref[i][c];
      sum += r * r;
      ++n;
    }
  return n ? std::sqrt(sum / n) : std::nan("");
}

}  // namespace

Suite ProbeSuite() {
  Suite s;
  s.name = "probe";
  s.summary = "gray-probe irradiance at 256 normals: quadrature of a W-wide sky vs SH-9";
  s.error_metric = "RMS rel. irradiance error vs quadrature of a converged CPU sky";
  s.error_axis = "RMS rel. irradiance error";
  s.run = [](const SuiteOptions& o) {
    Grid grid;
    const std::vector<std::string> widths = o.quick ? std::vector<std::string>{"32", "64", "128", "256"}
                                                    : std::vector<std::string>{"32", "64", "128", "256", "512"};
    // Default: the fit's probe_quadrature_width (fit/fit_options.h), by quadrature.
    grid.axes = {{"method", {"quadrature", "sh9"}, "quadrature"}, {"width", widths, "128"}};
    const render::Preset preset = render::LoadPreset(DefaultPresetPath());
    render::RenderRequest req;
    req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(35.0, 20.0);
    req.sun_disc = false;
    const auto normals = render::FibonacciSphere(256);
    auto cpu = render::CreateRenderer(render::Backend::kCpu);
    auto vulkan = render::CreateRenderer(render::Backend::kVulkan);
    render::RenderRequest ref_req = req;
    ref_req.width = o.quick ? 512 : 1024;
    ref_req.height = ref_req.width / 2;
    const std::vector<render::Rgb> truth = render::IrradianceQuadrature(cpu->Render(preset, ref_req), normals, 2);
    const int repeats = o.Repeats(o.quick ? 5 : 11);
    return RunGrid("probe", grid, o, [&](CaseResult& c) {
      render::RenderRequest rq = req;
      rq.width = std::stoi(Get(c.settings, "width"));
      rq.height = rq.width / 2;
      const bool sh = Get(c.settings, "method") == "sh9";
      std::vector<render::Rgb> e(normals.size());
      c.time = Measure(
          [&] {
            const ImageRGB sky = vulkan->Render(preset, rq);
            if (sh) {
              const render::ShCoefficients coeffs = render::ProjectSh9(sky);
              for (size_t i = 0; i < normals.size(); ++i) e[i] = render::ShIrradiance(coeffs, normals[i]);
            } else {
              e = render::IrradianceQuadrature(sky, normals, 2);
            }
          },
          o.warmup, repeats);
      c.error = RmsRel(truth, e);
      for (const auto& v : e)
        for (double x : v)
          if (!std::isfinite(x)) c.outcome = Outcome::kNonFinite;
    });
  };
  return s;
}

}  // namespace skycal::bench
