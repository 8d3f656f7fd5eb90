// Suite `clouds-error`: where the game march's added error comes from (docs/benchmarks.md). The
// clouds suite's scene, converged reference and error (rel RMSE of the composite above the
// horizon), for the naive march, the game's, each HZD optimisation switched on alone on top
// of the naive march and off alone from the game's settings, and the candidate settings that
// reduce the added error. Besides the error of the composite: the error over the
// reference's cloud pixels (T < 0.99) alone, its sign (brighter or darker than converged),
// and the squared error split by elevation band and by the reference's opacity, so that a
// row's added error can be located (the parts add up to the error squared). Vulkan only;
// time: one render at 512x256 (wall and process CPU time).
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cloud_scene.h"
#include "image_compare.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/composite.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/bench/timing.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

// The march axis: naive and game first, then each optimisation on alone, off alone, and
// the candidates for less added error (CloudMarchVariant's names).
const std::vector<std::string>& ErrorMarches() {
  static const std::vector<std::string> kMarches = {
      "naive", "game",
      "naive+cheap-march", "naive+cheap-march-no-step-back", "naive+opacity-stop", "naive+cheap-light", "naive+far-light",
      "no-cheap-march", "no-step-back", "no-return-to-cheap", "no-opacity-stop", "no-cheap-light", "no-far-light",
      "cheap-light-0.6", "cheap-light-0.9", "far-light-1500m", "far-light-6000m", "no-cheap-no-far-light"};
  return kMarches;
}

// Elevation bands (deg) and reference opacity classes the squared error is split into.
struct Band {
  const char* key;
  double lo, hi;
};
const Band kBands[] = {{"e2_elev_0_5", 0.0, 5.0}, {"e2_elev_5_15", 5.0, 15.0}, {"e2_elev_15_45", 15.0, 45.0},
                       {"e2_elev_45_90", 45.0, 90.01}};
// Reference transmittance T: clear (>= 0.99), thin (0.7..0.99), medium (0.1..0.7), thick (< 0.1).
const Band kOpacity[] = {{"e2_clear", 0.99, 1.01}, {"e2_thin", 0.7, 0.99}, {"e2_medium", 0.1, 0.7}, {"e2_thick", -1.0, 0.1}};

}  // namespace

void CloudErrorParts(const ConvergedCloudReference& ref, const ImageRGB& composite, CaseResult& c) {
  const ImageRGB& truth = ref.truth;
  std::map<std::string, double> part;
  double wsum = 0.0, cloud_sum = 0.0, cloud_w = 0.0, cloud_signed = 0.0;
  for (int y = 0; y < truth.height; ++y) {
    const double elev = latlong::Latitude(y, truth.height) * 180.0 / M_PI;
    if (elev <= 0.0) continue;
    for (int x = 0; x < truth.width; ++x) {
      const double w = latlong::PixelSolidAngle(x, y, truth.width, truth.height);
      bool ok = true;
      double r2 = 0.0, rs = 0.0;
      for (int ch = 0; ch < 3; ++ch) {
        const double t = truth.at(x, y, ch), v = composite.at(x, y, ch);
        ok = ok && std::isfinite(t) && t > 0.0 && std::isfinite(v) && v > 0.0;
        r2 += (v - t) * (v - t) / (t * t);
        rs += (v - t) / t;
      }
      if (!ok) continue;
      wsum += 3.0 * w;
      const double T = ref.clouds.transmittance[static_cast<size_t>(y) * truth.width + x];
      for (const Band& b : kBands)
        if (elev >= b.lo && elev < b.hi) part[b.key] += w * r2;
      for (const Band& b : kOpacity)
        if (T >= b.lo && T < b.hi) part[b.key] += w * r2;
      if (T < 0.99) {
        cloud_sum += w * r2;
        cloud_signed += w * rs;
        cloud_w += 3.0 * w;
      }
    }
  }
  for (const auto& [key, sum] : part) c.extra[key] = 1e4 * sum / wsum;  // %^2
  c.extra["rel_rmse_cloud_pixels"] = cloud_w > 0.0 ? std::sqrt(cloud_sum / cloud_w) : 0.0;
  c.extra["mean_rel_error_cloud_pixels"] = cloud_w > 0.0 ? cloud_signed / cloud_w : 0.0;
}

namespace {

// The suite's table: per row the errors, the points it adds over the naive march, and where
// its squared error sits.
std::string ErrorTable(const std::vector<CaseResult>& cases) {
  double naive = std::nan("");
  for (const CaseResult& c : cases)
    if (Get(c.settings, "march") == "naive") naive = c.error;
  std::vector<TableColumn> cols = {
      {"added (points)", [naive](const CaseResult& c) { return FormatFixed(100.0 * (c.error - naive), 2); }},
      {"cloud px rel RMSE %", [](const CaseResult& c) { return ExtraNumber(c, "rel_rmse_cloud_pixels", 100.0); }},
      {"cloud px mean signed %", [](const CaseResult& c) { return ExtraNumber(c, "mean_rel_error_cloud_pixels", 100.0); }},
      {"CPU ms", [](const CaseResult& c) { return ExtraNumber(c, "cpu_time_ms"); }}};
  for (const Band& b : kBands) cols.push_back({b.key, [key = std::string(b.key)](const CaseResult& c) { return ExtraNumber(c, key); }});
  for (const Band& b : kOpacity) cols.push_back({b.key, [key = std::string(b.key)](const CaseResult& c) { return ExtraNumber(c, key); }});
  return "# clouds-error: where the game march's added error sits\n\n"
         "Error: rel RMSE of the composite above the horizon vs the converged reference (the clouds suite's). "
         "`added`: points over the naive march. `e2_*`: that row's squared error (%^2) by elevation band (deg) and "
         "by the reference's transmittance (clear >= 0.99, thin 0.7-0.99, medium 0.1-0.7, thick < 0.1); each "
         "split sums to the error squared. Mean signed > 0: the clouds brighter than converged.\n\n" +
         CaseTable(cases, "rel RMSE", cols);
}

}  // namespace

Suite CloudsErrorSuite() {
  Suite s;
  s.name = "clouds-error";
  s.summary = "where the HZD cloud march's added error sits: each optimisation alone on the naive march and alone off the game's, candidates";
  s.error_metric = "rel RMSE of the composite above the horizon vs a converged double reference (the clouds suite's)";
  s.error_axis = "rel RMSE vs converged clouds";
  s.markdown = ErrorTable;
  s.run = [](const SuiteOptions& o) {
    const CloudBenchScene scene = LoadDefaultCloudyScene();
    Grid grid;
    grid.axes = {{"march", o.quick ? std::vector<std::string>{"naive", "game", "no-cheap-light"} : ErrorMarches(), "game"}};
    const clouds::CloudRenderRequest error_req = CloudSuiteRequest(o.quick ? 64 : 256);
    const clouds::CloudRenderRequest time_req = CloudSuiteRequest(o.quick ? 128 : 512);
    const ConvergedCloudReference ref = MakeConvergedCloudReference(scene, error_req, o);
    std::unique_ptr<clouds::CloudRenderer> vulkan = clouds::CreateVulkanCloudRenderer();
    const int repeats = o.Repeats(o.quick ? 3 : 5);
    return RunGrid("clouds-error", grid, o, [&](CaseResult& c) {
      clouds::CloudRenderRequest er = error_req, tr = time_req;
      er.march = tr.march = CloudMarchVariant(Get(c.settings, "march"));
      const ImageRGB composite = clouds::CompositeClouds(ref.sky, vulkan->Render(scene.View(), er));
      TimeCloudRender(*vulkan, scene, tr, o, repeats, c);
      if (!AllFinite(composite)) {
        c.outcome = Outcome::kNonFinite;
        c.message = "non-finite composite";
      }
      c.error = RelRmse(ref.truth, composite, 0.0);
      CloudErrorParts(ref, composite, c);
      c.extra["device"] = vulkan->Describe();
    });
  };
  return s;
}

}  // namespace skycal::bench
