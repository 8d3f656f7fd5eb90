#include "bake_verb.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>

#include "args.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

constexpr const char* kHelp = R"(skycal bake: a sky preset from a single-scattering Earth atmosphere

  skycal bake --out PRESET.json [--name NAME] [--haziness G] [--model ffxv|ffxv-iso]
              [--n-theta N] [--n-gamma N] [--mie-scattering PER_M] [--rayleigh-scale-height M]
              [--mie-scale-height M] [--observer-altitude M] [--json]

Defaults: Bruneton 2017 / Hillaire 2020 Earth (see render/include/skycal/render/atmosphere_bake.h),
sun 128000 lux, LUT grid 37 x 32. The bundled preset datasets/presets/default_clear.json is
`skycal bake --out datasets/presets/default_clear.json`.
)";

}  // namespace

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

int RunBake(int argc, char** argv) {
  if (WantsHelp(argc, argv)) {
    std::cout << kHelp;
    return 0;
  }
  return RunVerb("bake", WantsJson(argc, argv), [&]() {
    Args a(argc, argv,
           {"out", "name", "haziness", "model", "n-theta", "n-gamma", "mie-scattering", "rayleigh-scale-height",
            "mie-scale-height", "observer-altitude"},
           {"json"});
    BakeOptions o;
    o.out_json = a.Value("out").value_or("");
    if (auto v = a.Value("name")) o.name = *v;
    if (auto v = a.Number("haziness")) {
      if (!(*v >= 0.0 && *v <= 0.999)) throw Error("--haziness: expected g in [0, 0.999]");
      o.haziness_g = *v;
    }
    if (auto v = a.Value("model")) o.variant = render::ParseModelVariant(*v, "--model");
    auto count = [&](const char* name, int* out) {
      if (auto v = a.Number(name)) {
        if (*v != std::floor(*v) || *v < 2 || *v > 1024) throw Error(std::string("--") + name + ": expected an integer in [2, 1024]");
        *out = static_cast<int>(*v);
      }
    };
    count("n-theta", &o.grid.n_theta);
    count("n-gamma", &o.grid.n_gamma);
    if (auto v = a.Number("mie-scattering")) {
      o.atmosphere.mie_scattering_per_m = *v;
      o.atmosphere.mie_extinction_per_m = *v * (4.440 / 3.996);  // keep Hillaire's albedo 0.9
    }
    if (auto v = a.Number("rayleigh-scale-height")) o.atmosphere.rayleigh_scale_height_m = *v;
    if (auto v = a.Number("mie-scale-height")) o.atmosphere.mie_scale_height_m = *v;
    if (auto v = a.Number("observer-altitude")) o.atmosphere.observer_altitude_m = *v;
    return RunBakeImpl(o);
  });
}

}  // namespace skycal::cli
