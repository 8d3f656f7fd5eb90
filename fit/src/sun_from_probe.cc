// The probe's samples file ("skycal-probe-samples", written by `skycal probe-extract`) and
// the preset's sun tint from a probed sun. The sun itself is fitted jointly with the sky
// (fit/src/probe_cost.h, fit/src/sky_fit.cc).
#include "sun_from_probe.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_file.h"
#include "skycal/core/json_schema.h"
#include "skycal/render/preset.h"  // SunTransmittance

namespace skycal::fit {

namespace {

// A sample's pixel count when `v` is an integer in [1, 2^31); nullopt otherwise. Checked
// before the conversion: get<int> of 3.7e62 overflowed, and an integer beyond int wrapped
// (found by fuzz/probe_samples_fuzzer).
std::optional<int> PixelCount(const nlohmann::json& v) {
  constexpr std::int64_t kMax = std::numeric_limits<int>::max();
  if (!v.is_number_integer()) return std::nullopt;
  if (v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(kMax)) return std::nullopt;
  const std::int64_t n = v.get<std::int64_t>();
  if (n < 1 || n > kMax) return std::nullopt;
  return static_cast<int>(n);
}

}  // namespace

ProbeSamples ProbeSamplesFromJson(const nlohmann::json& doc, const std::string& origin) {
  auto fail = [&](const std::string& what) -> void { throw Error(origin + ": " + what); };
  if (!doc.is_object() || doc.value("format", std::string()) != "skycal-probe-samples") {
    fail("not a probe samples file (expected \"format\": \"skycal-probe-samples\")");
  }
  RequireFormatVersion(doc, 1, origin, "extract it again with skycal probe-extract");
  RequireKnownKeys(doc, {"format", "format_version", "image", "sha256", "circle", "circle_source", "camera_rotation", "albedo",
                         "clip_level", "max_luminance", "max_luminance_clipped", "pixels", "samples"},
                   origin, "");
  ProbeSamples p;
  p.path = origin;
  try {
    p.albedo = doc.at("albedo").get<double>();
    if (doc.contains("max_luminance") && doc["max_luminance"].is_number()) p.max_luminance = doc["max_luminance"].get<double>();
    p.max_luminance_clipped = doc.value("max_luminance_clipped", false);
    if (!doc.at("samples").is_array()) fail("field 'samples': expected an array");
    size_t i = 0;
    for (const auto& s : doc.at("samples")) {
      const std::string field = "samples[" + std::to_string(i++) + "]";
      RequireKnownKeys(s, {"normal", "radiance", "pixels"}, origin, field + ".");
      capture::ProbeSample ps;
      ps.normal = s.at("normal").get<std::array<double, 3>>();
      ps.radiance = s.at("radiance").get<std::array<double, 3>>();
      const std::optional<int> pixels = s.contains("pixels") ? PixelCount(s["pixels"]) : 1;
      if (!pixels) fail("field '" + field + ".pixels': expected a positive integer count below 2^31, got " + s["pixels"].dump());
      ps.pixels = *pixels;
      const double n = std::sqrt(ps.normal[0] * ps.normal[0] + ps.normal[1] * ps.normal[1] + ps.normal[2] * ps.normal[2]);
      if (!(std::abs(n - 1.0) < 1e-3)) fail("field '" + field + ".normal': expected a unit vector, its length is " + FormatNumber(n));
      for (int c = 0; c < 3; ++c) {
        // Radiance bounds: >= 0 and below 1e12 cd/m^2 (the sun's disc is ~1.6e9): a larger
        // value is corrupt and would overflow the fit's squared residuals.
        if (!(ps.radiance[c] >= 0.0 && ps.radiance[c] < 1e12)) {
          fail("field '" + field + ".radiance': expected values in [0, 1e12) cd/m^2, got " + FormatNumber(ps.radiance[c]));
        }
      }
      p.samples.push_back(ps);
    }
  } catch (const nlohmann::json::exception& e) {
    fail(std::string("malformed samples: ") + e.what());
  }
  if (!(p.albedo > 0.0 && p.albedo <= 1.0)) fail("field 'albedo': expected a value in (0, 1], got " + FormatNumber(p.albedo));
  if (p.samples.empty()) fail("no samples");
  return p;
}

ProbeSamples LoadProbeSamples(const std::string& path) { return ProbeSamplesFromJson(ReadJsonFile(path), path); }

std::array<double, 3> SunTintFor(const render::Preset& preset, const std::array<double, 3>& sun_dir,
                                 const std::array<double, 3>& illuminance_model, bool* clamped) {
  double lo = 0.0, hi = 10.0;
  for (const auto& spec : render::PresetParameterSpecs()) {
    if (std::string(spec.name) == "sun_tint_rgb") lo = spec.min, hi = spec.max;
  }
  const double n = std::sqrt(sun_dir[0] * sun_dir[0] + sun_dir[1] * sun_dir[1] + sun_dir[2] * sun_dir[2]);
  const double zenith = std::acos(std::clamp(sun_dir[1] / n, -1.0, 1.0));
  const auto t = render::SunTransmittance(preset.luts, zenith);
  std::array<double, 3> tint{};
  bool any = false;
  for (int c = 0; c < 3; ++c) {
    const double denom = preset.sun_illuminance_lux * t[c];
    double v = denom > 0.0 ? illuminance_model[c] / denom : hi;
    if (!std::isfinite(v) || v < lo || v > hi) {
      v = std::clamp(std::isfinite(v) ? v : hi, lo, hi);
      any = true;
    }
    tint[c] = v;
  }
  if (clamped) *clamped = any;
  return tint;
}

}  // namespace skycal::fit
