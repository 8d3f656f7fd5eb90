#include "import_verb.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <vector>

#include "command_line.h"
#include "finite_output.h"
#include "option_values.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"
#include "skycal/core/format_number.h"
#include "skycal/core/sha256.h"
#include "skycal/skysun/find_sun.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

struct PixelCensus {
  long long negative = 0, nan = 0, inf = 0;  // pixels with at least one such channel
  double max = 0.0, mean = 0.0;              // over finite values of every channel
};

PixelCensus Census(const ImageRGB& img) {
  PixelCensus c;
  double sum = 0.0;
  long long n = 0;
  for (size_t i = 0; i + 2 < img.pixels.size(); i += 3) {
    bool neg = false, nan = false, inf = false;
    for (int k = 0; k < 3; ++k) {
      const float v = img.pixels[i + k];
      if (std::isnan(v)) {
        nan = true;
      } else if (std::isinf(v)) {
        inf = true;
      } else {
        if (v < 0.0f) neg = true;
        c.max = std::max(c.max, static_cast<double>(v));
        sum += v;
        ++n;
      }
    }
    c.negative += neg;
    c.nan += nan;
    c.inf += inf;
  }
  c.mean = n ? sum / n : 0.0;
  return c;
}

nlohmann::json ToJson(const PixelCensus& c) {
  return {{"negative", c.negative}, {"nan", c.nan}, {"inf", c.inf}, {"max", c.max}, {"mean", c.mean}};
}

}  // namespace

SourceConvention ParseSourceConvention(const std::string& text, const std::string& option) {
  if (text == "blender") return SourceConvention::kBlender;
  if (text == "exr") return SourceConvention::kExr;
  throw Error(option + ": unknown convention '" + text + "' (expected blender or exr)");
}

bool ImportOptions::IsValid(std::string* why) const {
  if (in_path.empty()) {
    *why = "--in SRC.exr is required";
    return false;
  }
  if (out_path.empty() || !EndsWith(out_path, ".exr")) {
    *why = "--out: expected an output path ending in .exr";
    return false;
  }
  if (sun_dir && detect_sun) {
    *why = "give either --sun-dir or --detect-sun, not both";
    return false;
  }
  if (sun_dir) {
    const auto& d = *sun_dir;
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!std::isfinite(n) || !(n > 1e-9)) {
      *why = "--sun-dir: expected a finite, non-zero vector";
      return false;
    }
  }
  if (!(min_sun_contrast >= 1.0)) {
    *why = "--min-sun-contrast: expected a ratio >= 1";
    return false;
  }
  return true;
}

namespace {
// The frame's sun: --sun-dir, --detect-sun, or the source's own sunDirection attribute;
// returns import --json's `sun` object (null when none) and names its source.
struct ImportedSun {
  nlohmann::json json = nullptr;
  std::string source = "none";
};

ImportedSun ImportSun(const ImportOptions& o, const ExrRGB& src, capture::LatLongFrame* frame, nlohmann::json* warnings) {
  std::string why;
  ImportedSun is;
  nlohmann::json& sun = is.json;
  std::string& sun_source = is.source;
  if (o.sun_dir) {
    frame->sun_direction = latlong::Normalized(*o.sun_dir, "--sun-dir");
    sun_source = "option";
  } else if (o.detect_sun) {
    const auto f = skysun::FindSun(frame->radiance, o.min_sun_contrast, skysun::SkySunOptions{}, &why);
    if (!f) throw Error(o.in_path + ": --detect-sun: " + why + "; nothing written");
    frame->sun_direction = f->direction;
    if (f->source == "disc") {
      sun_source = "detected";
      sun = {{"contrast", f->disc_contrast},
             {"peak_luminance", f->disc_peak_luminance},
             {"region_pixels", f->disc_region_pixels},
             {"clipped", f->disc_clipped}};
      if (f->disc_clipped) {
        warnings->push_back(o.in_path + ": the sun is clipped (a plateau at " + std::to_string(f->disc_peak_luminance) +
                            "): its disc radiance is unknown; the fit masks the sun cone and clipped pixels");
      }
    } else {
      sun_source = "sky-estimate";
      sun = {{"uncertainty_deg", f->uncertainty_deg},
             {"log_rmse", f->sky->log_rmse},
             {"cie_type", f->sky->sky_type},
             {"no_disc", f->disc_refusal}};
      frame->extra.floats["skycalSunUncertaintyDeg"] = static_cast<float>(f->uncertainty_deg);
      warnings->push_back(o.in_path + ": no sun disc (" + f->disc_refusal +
                          "): the sun is placed from the sky's luminance pattern, uncertain by " +
                          FormatNumber(f->uncertainty_deg) + " deg (docs/capture.md)");
    }
  } else if (o.convention == SourceConvention::kExr) {
    if (auto it = src.attributes.v3fs.find("sunDirection"); it != src.attributes.v3fs.end()) {
      const auto& v = it->second;
      frame->sun_direction = latlong::Normalized({v[0], v[1], v[2]}, (o.in_path + ": attribute 'sunDirection'").c_str());
      sun_source = "attribute";
    }
  }
  if (frame->sun_direction) {
    const auto& s = *frame->sun_direction;
    if (sun.is_null()) sun = nlohmann::json::object();
    sun["direction"] = s;
    sun["elevation_deg"] = latlong::ElevationDeg(s);
    sun["azimuth_deg"] = latlong::AzimuthDeg(s);
    sun["source"] = sun_source;
  }
  return is;
}
}  // namespace

nlohmann::json RunImportImpl(const ImportOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  namespace fs = std::filesystem;
  RefuseOutputsOverInputs({{"--out", o.out_path}}, {{"--in", o.in_path}});
  { AtomicOutput probe(o.out_path); }  // fail on an unwritable output before reading

  ExrRGB src = ReadExrRGB(o.in_path);
  RequireValidShare(o.in_path, src.image);
  const std::string sha = Sha256OfFile(o.in_path);
  const int w = src.image.width, h = src.image.height;
  if (w != 2 * h || h < 2) {
    throw Error(o.in_path + ": image is " + std::to_string(w) + "x" + std::to_string(h) +
                ", expected a 2:1 equirectangular panorama (width = 2 x height)");
  }
  nlohmann::json warnings = nlohmann::json::array();
  if (o.convention == SourceConvention::kBlender && src.attributes.envmap_latlong) {
    warnings.push_back(o.in_path + " carries envmap=latlong (the project's convention?) but is read as blender; "
                       "pass --source-convention exr if it is already a skycal frame");
  }
  const PixelCensus src_census = Census(src.image);

  capture::LatLongFrame frame;
  frame.radiance = ResampleToProjectLatLong(src.image, o.convention, w, h);
  const PixelCensus out_census = Census(frame.radiance);
  if (src_census.negative + src_census.nan + src_census.inf > 0) {
    warnings.push_back(o.in_path + ": " + std::to_string(src_census.negative) + " negative, " +
                       std::to_string(src_census.nan) + " NaN, " + std::to_string(src_census.inf) +
                       " Inf pixels (lossy-compression ringing?): non-finite ones written as 0, which the fit masks like negative ones");
  }

  const ImportedSun imported_sun = ImportSun(o, src, &frame, &warnings);
  const nlohmann::json& sun = imported_sun.json;
  const std::string& sun_source = imported_sun.source;

  const std::string file_name = fs::path(o.in_path).filename().string();
  frame.extra.strings["skycalSource"] = file_name + " sha256:" + sha;
  frame.extra.strings["skycalSourceConvention"] = ToString(o.convention);
  frame.extra.strings["skycalSunSource"] = sun_source;
  frame.extra.strings["skycalUnits"] = "relative scene-linear Rec.709 (source not calibrated: exposure unknown)";
  const FiniteOutputCounts written = PrepareImageForWrite("import", o.out_path, &frame.radiance, o.half);
  capture::WriteLatLongFrame(o.out_path, frame, o.half);

  for (const auto& wmsg : warnings) Log("import", "warning: " + wmsg.get<std::string>());
  std::string sun_text = ", no sun direction";
  if (frame.sun_direction) {
    sun_text = ", sun elevation " + std::to_string(latlong::ElevationDeg(*frame.sun_direction)) + " deg azimuth " +
               std::to_string(latlong::AzimuthDeg(*frame.sun_direction)) + " deg (" + sun_source + ")";
  }
  Log("import", "wrote " + o.out_path + " (" + std::to_string(w) + "x" + std::to_string(h) + ", from " + file_name + ", " +
                    ToString(o.convention) + " convention" + sun_text + ")");
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  return {{"in", o.in_path},
          {"out", o.out_path},
          {"source",
           {{"file", file_name},
            {"sha256", sha},
            {"size", {w, h}},
            {"channels", src.channels},
            {"convention", ToString(o.convention)},
            {"envmap_latlong_attribute", src.attributes.envmap_latlong}}},
          {"size", {w, h}},
          {"pixels", {{"source", ToJson(src_census)}, {"output", ToJson(out_census)}}},
          {"sun", sun},
          {"half", o.half},
          {"written_as_zero", written.non_finite},
          {"half_clamped", written.half_clamped},
          {"time_ms", ms},
          {"warnings", warnings}};
}

ImportOptions ParseImportArgs(int argc, char** argv) {
  VerbCommandLine cl("import", "skycal import: convert a published equirectangular HDR sky to a reference frame",
                     "  skycal import --in SRC.exr --out FRAME.exr [--sun-dir X,Y,Z | --detect-sun]\n"
                     "                [--source-convention blender|exr] [--half] [--json]",
                     "Pixels are resampled bilinearly (wrapping in longitude). Negative, NaN and Inf source pixels\n"
                     "(e.g. DWAB ringing) are counted in the summary and masked: the fit leaves values <= 0 out;\n"
                     "NaN and Inf are written as 0 (no non-finite value is written).");
  ImportOptions o;
  std::optional<std::string> sun_dir, convention;
  bool json = false;
  cl.Text("--in", &o.in_path, "SRC.exr", "RGB(A) OpenEXR, half or float, any compression (DWAB included; required)");
  cl.Text("--out", &o.out_path, "FRAME.exr",
          "output frame: the project's lat-long (OpenEXR envmap LatLong,\n"
          "+Y up, longitude 0 -> +Z, 90 deg -> +X), same size as the source (required)");
  cl.Text("--source-convention", &convention, "NAME",
          "blender (default: Blender / Poly Haven equirectangular, Z up,\n"
          "texel centres at (i + 0.5) / W) or exr (already this project's\n"
          "convention: nodes at i / (W - 1))");
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
