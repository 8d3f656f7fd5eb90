// Suite `export`: `skycal export` (exporter::ExportGameTables) of the bundled preset, grid over the
// pre-exposure headroom (the largest LUT texel is at most H x 65504). Time: the whole
// export (it hardly depends on H); error: RMS over the positive texels of the relative
// error of a LUT texel read back from the half-float EXR (divided by the pre-exposure)
// against the preset's float table: FP16's rounding (<= 2^-11) plus what underflows into
// subnormals or to 0 (error 1) when H is small, the price of headroom for the game's own
// multipliers when H is large.
#include <algorithm>
#include <cmath>

#include "skycal/export/game_export.h"
#include "skycal/core/exr_io.h"
#include "skycal/render/preset.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

Suite ExportSuite() {
  Suite s;
  s.name = "export";
  s.summary = "skycal export of the bundled preset: pre-exposure headroom";
  s.error_metric = "RMS rel. error of the half-float LUT texels vs the float tables (underflow to 0 counts 1)";
  s.error_axis = "RMS rel. error of half LUT texels";
  s.run = [](const SuiteOptions& o) {
    Grid grid;
    grid.axes = {{"headroom", {"1e-6", "1e-4", "0.01", "0.25", "1"}, "0.25"}};  // ExportOptions default
    const render::Preset preset = render::LoadPreset(DefaultPresetPath());
    const int repeats = o.Repeats(o.quick ? 3 : 7);
    int k = 0;
    return RunGrid("export", grid, o, [&](CaseResult& c) {
      exporter::ExportOptions eo;
      eo.presets = {DefaultPresetPath()};
      eo.headroom = std::stod(Get(c.settings, "headroom"));
      eo.backend = render::Backend::kCpu;
      eo.verbose = o.verb_logs;
      eo.report = false;  // the export's own work is timed, not the HTML report
      eo.out_dir = (o.scratch / ("export_" + std::to_string(k++))).string();
      nlohmann::json summary;
      c.time = Measure([&] { summary = exporter::ExportGameTables(eo); }, o.warmup, repeats);
      const double scale = summary.at("pre_exposure").get<double>();
      double sum = 0.0;
      long long n = 0;
      const std::string dir = eo.out_dir + "/" + summary.at("presets").at(0).at("name").get<std::string>();
      for (const auto& [name, table] : {std::pair{"rayleigh", &preset.luts.rayleigh}, std::pair{"mie", &preset.luts.mie}}) {
        const ImageRGB back = ReadExrRGB(dir + "/" + name + ".exr").image;
        for (size_t i = 0; i < table->size() && i < back.pixels.size(); ++i) {
          if (!((*table)[i] > 0.0f)) continue;
          const double r = std::abs(back.pixels[i] / scale - (*table)[i]) / (*table)[i];
          sum += r * r;
          ++n;
        }
      }
      c.error = n ? std::sqrt(sum / n) : NAN;
      c.extra = {{"pre_exposure", scale}, {"half_underflow_texels", summary.value("half_underflow_texels", 0LL)}};
      if (!std::isfinite(c.error)) {
        c.outcome = Outcome::kNonFinite;
        c.message = "a texel read back non-finite";
      }
    });
  };
  return s;
}

}  // namespace skycal::bench
