#include "import_verb.h"

#include <chrono>

#include "command_line.h"
#include "option_values.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

// The library names its ImportOptions fields; the user typed these flags.
constexpr FieldFlag kFlags[] = {{"ImportOptions::in_path", "--in"},
                                {"ImportOptions::out_path", "--out"},
                                {"ImportOptions::sun_dir", "--sun-dir"},
                                {"ImportOptions::detect_sun", "--detect-sun"},
                                {"ImportOptions::min_sun_contrast", "--min-sun-contrast"},
                                {"ImportOptions::convention", "--source-convention"},
                                {"ImportOptions::half", "--half"}};

// --source-convention's value; "auto" is nullopt (capture::ChooseConvention).
std::optional<capture::SourceConvention> ParseSourceConvention(const std::string& text, const std::string& option) {
  if (text == "blender") return capture::SourceConvention::kBlender;
  if (text == "exr") return capture::SourceConvention::kExr;
  if (text == "auto") return std::nullopt;
  throw Error(option + ": unknown convention '" + text + "' (expected blender, exr or auto)");
}

nlohmann::json ToJson(const controllers::PixelCensus& c) {
  return {{"negative", c.negative}, {"nan", c.nan}, {"inf", c.inf}, {"max", c.max}, {"mean", c.mean}};
}

// import --json's `sun` object: null when the frame has no sun.
nlohmann::json SunJson(const controllers::ImportedSun& s) {
  if (!s.direction) return nullptr;
  nlohmann::json sun = nlohmann::json::object();
  if (s.source == controllers::SunSource::kDisc) {
    sun = {{"contrast", s.disc_contrast},
           {"peak_luminance", s.disc_peak_luminance},
           {"region_pixels", s.disc_region_pixels},
           {"clipped", s.disc_clipped}};
  } else if (s.source == controllers::SunSource::kSkyEstimate) {
    sun = {{"uncertainty_deg", s.uncertainty_deg},
           {"log_rmse", s.sky_log_rmse},
           {"cie_type", s.sky_cie_type},
           {"no_disc", s.no_disc}};
  }
  sun["direction"] = *s.direction;
  sun["elevation_deg"] = latlong::ElevationDeg(*s.direction);
  sun["azimuth_deg"] = latlong::AzimuthDeg(*s.direction);
  sun["source"] = controllers::RecordedName(s.source);
  return sun;
}

// The log lines: what the writer zeroed or clamped, the warnings, what was written.
void LogImport(const controllers::ImportOptions& o, const controllers::ImportedFile& f, const nlohmann::json& warnings) {
  const controllers::ImportedPhoto& p = f.photo;
  if (p.zeroed > 0) {
    Log("import", o.out_path + ": " + std::to_string(p.zeroed) +
                      " non-finite values (NaN or inf: invalid input pixels) masked, written as 0");
  }
  if (f.half_clamped > 0) {
    Log("import", o.out_path + ": --half: " + std::to_string(f.half_clamped) +
                      " values above 65504 (the half-float maximum, e.g. at the sun) clamped to 65504; "
                      "write float (without --half) or lower the exposure to keep them");
  }
  for (const auto& wmsg : warnings) Log("import", "warning: " + wmsg.get<std::string>());
  std::string sun_text = ", no sun direction";
  if (p.sun.direction) {
    sun_text = ", sun elevation " + std::to_string(latlong::ElevationDeg(*p.sun.direction)) + " deg azimuth " +
               std::to_string(latlong::AzimuthDeg(*p.sun.direction)) + " deg (" +
               controllers::RecordedName(p.sun.source) + ")";
  }
  const int w = p.frame.radiance.width, h = p.frame.radiance.height;
  Log("import", "wrote " + o.out_path + " (" + std::to_string(w) + "x" + std::to_string(h) + ", from " + p.source_file +
                    ", " + capture::ToString(p.convention) + " convention" + sun_text + ")");
}

}  // namespace

nlohmann::json RunImportImpl(const controllers::ImportOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  controllers::ImportedFile f;
  try {
    f = controllers::ImportToFile(o);
  } catch (const Error& e) {
    throw Error(FieldsAsFlags(e.what(), kFlags));
  }
  const controllers::ImportedPhoto& p = f.photo;
  nlohmann::json warnings = nlohmann::json::array();
  for (const std::string& wmsg : p.warnings) warnings.push_back(FieldsAsFlags(wmsg, kFlags));
  LogImport(o, f, warnings);
  const int w = p.frame.radiance.width, h = p.frame.radiance.height;
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  return {{"in", o.in_path},
          {"out", o.out_path},
          {"source",
           {{"file", p.source_file},
            {"sha256", p.source_sha256},
            {"size", {w, h}},
            {"channels", p.source_channels},
            {"convention", capture::ToString(p.convention)},
            {"envmap_latlong_attribute", p.source_envmap_latlong}}},
          {"size", {w, h}},
          {"pixels", {{"source", ToJson(p.source_pixels)}, {"output", ToJson(p.frame_pixels)}}},
          {"sun", SunJson(p.sun)},
          {"half", o.half},
          {"written_as_zero", p.zeroed},
          {"half_clamped", f.half_clamped},
          {"time_ms", ms},
          {"warnings", warnings}};
}

controllers::ImportOptions ParseImportArgs(int argc, char** argv) {
  VerbCommandLine cl("import", "skycal import: convert a published equirectangular HDR sky to a reference frame",
                     "  skycal import --in SRC.exr|SRC.hdr --out FRAME.exr [--sun-dir X,Y,Z | --detect-sun]\n"
                     "                [--source-convention blender|exr|auto] [--half] [--json]",
                     "Pixels are resampled bilinearly (wrapping in longitude). Negative, NaN and Inf source pixels\n"
                     "(e.g. DWAB ringing) are counted in the summary and masked: the fit leaves values <= 0 out;\n"
                     "NaN and Inf are written as 0 (no non-finite value is written).");
  controllers::ImportOptions o;
  std::optional<std::string> sun_dir, convention;
  bool json = false;
  cl.Text("--in", &o.in_path, "SRC.exr|SRC.hdr",
          "RGB(A) OpenEXR, half or float, any compression (DWAB included), or a Radiance RGBE picture (.hdr; required)");
  cl.Text("--out", &o.out_path, "FRAME.exr",
          "output frame: the project's lat-long (OpenEXR envmap LatLong,\n"
          "+Y up, longitude 0 -> +Z, 90 deg -> +X), same size as the source (required)");
  cl.Text("--source-convention", &convention, "NAME",
          "blender (default: Blender / Poly Haven equirectangular, Z up,\n"
          "texel centres at (i + 0.5) / W), exr (already this project's\n"
          "convention: nodes at i / (W - 1)) or auto (exr when the file carries\n"
          "the envmap=latlong attribute, else blender)");
  cl.Text("--sun-dir", &sun_dir, "X,Y,Z", "sun direction in the OUTPUT frame (+Y up), written as sunDirection");
  cl.Flag("--detect-sun", &o.detect_sun,
          "find the sun in the converted frame: its disc, else placed from the\n"
          "sky's luminance pattern with an uncertainty (docs/capture.md); refuses\n"
          "(exit 1, nothing written) when neither places it");
  cl.Number("--min-sun-contrast", &o.min_sun_contrast, "C", "--detect-sun's peak / median luminance threshold (default 20)");
  cl.Flag("--half", &o.half, "write half floats (default float)");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  if (sun_dir) o.sun_dir = ParseVec3(*sun_dir, "--sun-dir");
  if (convention) o.convention = ParseSourceConvention(*convention, "--source-convention");
  return o;
}

int RunImport(int argc, char** argv) {
  return RunVerb("import", WantsJson(argc, argv), [&]() { return RunImportImpl(ParseImportArgs(argc, argv)); });
}

}  // namespace skycal::cli
