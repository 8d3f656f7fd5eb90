#include "bake_verb.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>

#include "command_line.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {
nlohmann::json RunBakeImpl(const BakeOptions& o) {
  std::string why;
  if (!o.atmosphere.IsValid(&why)) throw Error(why);
  if (o.out_json.size() < 6 || o.out_json.substr(o.out_json.size() - 5) != ".json") {
    throw Error("--out: expected a preset path ending in .json");
  }
  { AtomicOutput probe(o.out_json); }  // fail early on an unwritable destination
  const auto t0 = std::chrono::steady_clock::now();
  render::Preset p;
  p.name = o.name;
  p.variant = o.variant;
  p.haziness_g = o.haziness_g;
  p.sun_illuminance_lux = o.atmosphere.sun_illuminance_lux;
  p.luts.Resize(o.grid);
  render::BakeSingleScattering(o.atmosphere, p.luts);
  // Within the bounds a LUT can still come out black (e.g. a thick atmosphere seen from its
  // floor); a black table would let a later fit "succeed" at a large error: refuse it here.
  for (const auto& [name, table] : {std::pair<const char*, const std::vector<float>*>{"rayleigh", &p.luts.rayleigh},
                                    {"mie", &p.luts.mie}}) {
    if (*std::max_element(table->begin(), table->end()) <= 0.0f) {
      throw Error(std::string("bake: the ") + name +
                  " LUT came out entirely zero: the atmosphere is opaque for single scattering at these coefficients "
                  "(lower the scattering or extinction)");
    }
  }
  const double bake_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const nlohmann::json provenance = {
      {"provenance",
       {{"generator", "skycal bake (single scattering, render/src/atmosphere_bake.cc)"},
        {"atmosphere",
         {{"planet_radius_m", o.atmosphere.planet_radius_m},
          {"atmosphere_top_m", o.atmosphere.atmosphere_top_m},
          {"observer_altitude_m", o.atmosphere.observer_altitude_m},
          {"rayleigh_scattering_per_m", o.atmosphere.rayleigh_scattering_per_m},
          {"rayleigh_scale_height_m", o.atmosphere.rayleigh_scale_height_m},
          {"mie_scattering_per_m", o.atmosphere.mie_scattering_per_m},
          {"mie_extinction_per_m", o.atmosphere.mie_extinction_per_m},
          {"mie_scale_height_m", o.atmosphere.mie_scale_height_m},
          {"ozone_absorption_per_m", o.atmosphere.ozone_absorption_per_m},
          {"sun_illuminance_lux", o.atmosphere.sun_illuminance_lux}}},
        {"note", "isotropic table zero: multiple scattering is not baked; fit it with --model ffxv-iso"}}}};
  render::SavePreset(p, o.out_json, &provenance);
  Log("bake", "wrote " + o.out_json + " (" + std::to_string(o.grid.n_theta) + "x" + std::to_string(o.grid.n_gamma) +
                  " LUTs, " + std::to_string(bake_s) + " s)");
  return {{"out", o.out_json}, {"time_s", bake_s}, {"grid", {o.grid.n_theta, o.grid.n_gamma}}};
}

BakeOptions ParseBakeArgs(int argc, char** argv) {
  VerbCommandLine cl("bake", "skycal bake: a sky preset from a single-scattering Earth atmosphere",
                     "  skycal bake --out PRESET.json [--name NAME] [--haziness G] [--model ffxv|ffxv-iso]\n"
                     "              [--n-theta N] [--n-gamma N] [--mie-scattering PER_M] [--rayleigh-scale-height M]\n"
                     "              [--mie-scale-height M] [--observer-altitude M] [--json]",
                     "Defaults: Bruneton 2017 / Hillaire 2020 Earth (see render/include/skycal/render/atmosphere_bake.h),\n"
                     "sun 128000 lux, LUT grid 37 x 32. The bundled preset datasets/presets/default_clear.json is\n"
                     "`skycal bake --out datasets/presets/default_clear.json`.");
  BakeOptions o;
  std::optional<std::string> model;
  std::optional<double> mie_scattering;
  bool json = false;
  cl.Text("--out", &o.out_json, "PRESET.json", "preset JSON to write (required); the LUT EXRs go beside it");
  cl.Text("--name", &o.name, "NAME", "the preset's name (default default_clear)");
  cl.Number("--haziness", &o.haziness_g, "G", "Cornette-Shanks g written into the preset, in [0, 0.999] (default 0.8)")
      ->check(NumberIn(0.0, 0.999, "expected g in [0, 0.999]"));
  cl.Text("--model", &model, "NAME", "model variant written into the preset: ffxv (default) or ffxv-iso");
  cl.Integer("--n-theta", &o.grid.n_theta, 2, 1024, "expected an integer in [2, 1024]", "N",
             "LUT rows (sun zenith), integer in [2, 1024] (default 37)");
  // The renderers' limit (render/model/limits.glsl.h), checked here rather than after the bake.
  const std::string columns = "[2, " + std::to_string(render::kMaxLutColumns) + "]";
  cl.Integer("--n-gamma", &o.grid.n_gamma, 2, render::kMaxLutColumns, "expected an integer in " + columns, "N",
             "LUT columns (view elevation), integer in " + columns + " (default 32)");
  cl.Number("--mie-scattering", &mie_scattering, "PER_M",
            "Mie scattering coefficient at sea level, 1/m (default 3.996e-6); the extinction\n"
            "follows at 4.440/3.996 of it (Hillaire's single-scattering albedo 0.9)");
  cl.Number("--rayleigh-scale-height", &o.atmosphere.rayleigh_scale_height_m, "M",
            "Rayleigh density scale height in metres (default 8000)");
  cl.Number("--mie-scale-height", &o.atmosphere.mie_scale_height_m, "M",
            "Mie density scale height in metres (default 1200)");
  cl.Number("--observer-altitude", &o.atmosphere.observer_altitude_m, "M",
            "observer altitude above the planet surface in metres (default 200)");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  if (model) o.variant = render::ParseModelVariant(*model, "--model");
  if (mie_scattering) {
    o.atmosphere.mie_scattering_per_m = *mie_scattering;
    o.atmosphere.mie_extinction_per_m = *mie_scattering * (4.440 / 3.996);  // keep Hillaire's albedo 0.9
  }
  return o;
}

int RunBake(int argc, char** argv) {
  return RunVerb("bake", WantsJson(argc, argv), [&]() { return RunBakeImpl(ParseBakeArgs(argc, argv)); });
}

}  // namespace skycal::cli
