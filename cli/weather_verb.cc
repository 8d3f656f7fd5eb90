#include "weather_verb.h"

#include <algorithm>
#include <numeric>

#include "command_line.h"
#include "skycal/core/error.h"
#include "skycal/core/output_kind.h"
#include "verb_common.h"

namespace skycal::cli {

bool WeatherOptions::IsValid(std::string* why) const {
  if (out.empty()) {
    *why = "--out W.exr is required";
    return false;
  }
  if (!noise.IsValid(why)) return false;
  try {
    clouds::CheckWeatherMapSize(size, size, "--size");
  } catch (const Error& e) {
    *why = e.what();
    return false;
  }
  if (size < 2 * noise.coverage_cells) {
    *why = "--size " + std::to_string(size) + ": expected at least 2 x --coverage-cells (" +
           std::to_string(2 * noise.coverage_cells) + " texels)";
    return false;
  }
  if (!(extent_m > 0.0 && extent_m <= clouds::kMaxWeatherExtentM)) {
    *why = "--extent: expected metres in (0, 1e6]";
    return false;
  }
  return true;
}

nlohmann::json RunWeatherImpl(const WeatherOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  RequireExtension("--out", o.out, {".exr"}, "the weather map (OpenEXR)");
  Log("weather", "procedural map, seed " + std::to_string(o.seed) + ", " + std::to_string(o.size) + "x" +
                     std::to_string(o.size) + " over " + std::to_string(static_cast<int>(o.extent_m)) + " m");
  const clouds::WeatherMap map = clouds::NoiseWeatherMap(static_cast<uint64_t>(o.seed), o.size, o.extent_m, o.noise);
  clouds::SaveWeatherMap(map, o.out);  // validates, then temp + rename
  // What the map holds, per channel: mean, min, max (a user checks the coverage asked for).
  nlohmann::json channels = nlohmann::json::object();
  const char* names[3] = {"coverage", "precipitation", "type"};
  const size_t n = static_cast<size_t>(map.width) * map.height;
  for (int c = 0; c < 3; ++c) {
    double sum = 0.0, lo = 1.0, hi = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double v = map.rgb[i * 3 + c];
      sum += v;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    channels[names[c]] = {{"mean", sum / n}, {"min", lo}, {"max", hi}};
  }
  Log("weather", "wrote " + o.out + " (mean coverage " + std::to_string(channels["coverage"]["mean"].get<double>()) + ")");
  return {{"out", o.out}, {"size", o.size}, {"extent_m", o.extent_m}, {"seed", o.seed}, {"channels", channels}};
}

WeatherOptions ParseWeatherArgs(int argc, char** argv) {
  VerbCommandLine cl("weather",
                     "skycal weather: a procedural weather map for the clouds (R coverage, G precipitation,\n"
                     "B type: 0 stratus, 0.5 cumulus, 1 cumulonimbus), as an RGB EXR to paint over or use as is",
                     "  skycal weather --out W.exr [--seed N] [--size S] [--extent M] [--mean-coverage C]\n"
                     "                 [--coverage-contrast K] [--coverage-cells N] [--octaves N] ...",
                     "Each field is tileable noise remapped to its mean exactly (up to 1e-4) and scaled about it\n"
                     "by its contrast. Coverage: Perlin fBm dilated by Worley fBm (Horizon Zero Dawn's\n"
                     "Perlin-Worley, for billowy patches). Map row 0 covers -z (see docs/cloud-model.md, weather maps).");
  WeatherOptions o;
  clouds::WeatherNoiseOptions& n = o.noise;
  cl.Text("--out", &o.out, "W.exr", "the weather map EXR (written atomically)");
  cl.Integer("--seed", &o.seed, 0, 2147483647.0, "expected an integer in [0, 2^31)", "N", "noise seed (default 1)");
  cl.Integer("--size", &o.size, 4, 4096, "expected a power of two in [4, 4096]", "S", "texels a side (default 256)");
  cl.Number("--extent", &o.extent_m, "M", "world metres the map covers along x and z (default 60000)")
      ->check(NumberIn(1.0, clouds::kMaxWeatherExtentM, "expected metres in [1, 1e6]"));
  cl.Number("--mean-coverage", &n.mean_coverage, "C", "mean of R, [0, 1] (default 0.5)")
      ->check(NumberIn(0.0, 1.0, "expected a fraction in [0, 1]"));
  cl.Number("--coverage-contrast", &n.coverage_contrast, "K", "coverage deviations scaled by K, [0, 16] (default 1.5)")
      ->check(NumberIn(0.0, 16.0, "expected a factor in [0, 16]"));
  cl.Integer("--coverage-cells", &n.coverage_cells, 1, 1024, "expected an integer in [1, 1024]", "N",
             "noise cells across the map (default 4)");
  cl.Number("--mean-precipitation", &n.mean_precipitation, "P", "mean of G, [0, 1] (default 0.1)")
      ->check(NumberIn(0.0, 1.0, "expected a fraction in [0, 1]"));
  cl.Number("--precipitation-contrast", &n.precipitation_contrast, "K", "[0, 16] (default 1)")
      ->check(NumberIn(0.0, 16.0, "expected a factor in [0, 16]"));
  cl.Number("--mean-type", &n.mean_type, "T", "mean of B, [0, 1] (default 0.5: cumulus)")
      ->check(NumberIn(0.0, 1.0, "expected a fraction in [0, 1]"));
  cl.Number("--type-contrast", &n.type_contrast, "K", "[0, 16] (default 1)")
      ->check(NumberIn(0.0, 16.0, "expected a factor in [0, 16]"));
  cl.Integer("--octaves", &n.octaves, 1, 8, "expected an integer in [1, 8]", "N", "fBm octaves (default 4)");
  bool json = false;
  cl.Flag("--json", &json, "print a JSON summary on stdout (per channel mean, min, max)");
  cl.Parse(argc, argv);
  return o;
}

int RunWeather(int argc, char** argv) {
  return RunVerb("weather", WantsJson(argc, argv), [&]() { return RunWeatherImpl(ParseWeatherArgs(argc, argv)); });
}

}  // namespace skycal::cli
