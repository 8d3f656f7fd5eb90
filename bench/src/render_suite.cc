// Suite `render`: the sky renderer, backend x size. Time: one Render call (readback
// included) of the bundled default preset, sun 35 deg elevation, no sun disc. Error: what a
// game sees when it renders the sky at that size and samples it bilinearly: rel RMSE above
// the horizon against the CPU double reference at twice the largest size.
#include <map>
#include <memory>

#include "image_compare.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

Suite RenderSuite() {
  Suite s;
  s.name = "render";
  s.summary = "sky render of the bundled preset (sun 35 deg, no disc): backend x size";
  s.error_metric = "rel RMSE above the horizon vs CPU reference at 2x the largest size (bilinear)";
  s.error_axis = "rel RMSE vs a 2x-size CPU sky";
  s.run = [](const SuiteOptions& o) {
    Grid grid;
    const std::vector<std::string> sizes = o.quick ? std::vector<std::string>{"256x128", "512x256", "1024x512"}
                                                   : std::vector<std::string>{"256x128", "512x256", "1024x512", "2048x1024"};
    grid.axes = {{"backend", {"vulkan", "cpu"}, "vulkan"}, {"size", sizes, "1024x512"}};  // render verb's defaults
    const render::Preset preset = render::LoadPreset(DefaultPresetPath());
    render::RenderRequest req;
    req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(35.0, 20.0);
    req.sun_disc = false;
    req.ground = render::GroundMode::kZero;
    auto renderers = SkyRenderersByBackend();
    render::RenderRequest ref_req = req;
    ref_req.width = o.quick ? 2048 : 4096;
    ref_req.height = ref_req.width / 2;
    o.Log("[render] reference: cpu " + std::to_string(ref_req.width) + "x" + std::to_string(ref_req.height));
    const ImageRGB truth = renderers["cpu"]->Render(preset, ref_req);
    const int repeats = o.Repeats(o.quick ? 5 : 11);
    return RunGrid("render", grid, o, [&](CaseResult& c) {
      render::SkyRenderer& r = *renderers.at(Get(c.settings, "backend"));
      render::RenderRequest rq = req;
      const std::string& size = Get(c.settings, "size");
      rq.width = std::stoi(size.substr(0, size.find('x')));
      rq.height = rq.width / 2;
      ImageRGB image;
      c.time = Measure([&] { image = r.Render(preset, rq); }, o.warmup, repeats);
      if (!AllFinite(image)) {
        c.outcome = Outcome::kNonFinite;
        c.message = "non-finite radiance";
      }
      c.error = RelRmse(truth, image, 0.0);
      c.extra["device"] = r.Describe();
    });
  };
  return s;
}

}  // namespace skycal::bench
