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

// Blender's equirectangular mapping (Cycles kernel/geom `direction_to_equirectangular`,
// range (-2pi, pi, -pi, pi); EEVEE `node_tex_environment_equirectangular`), for a world
// direction b (Blender is Z up):
//   u = -atan2(b.y, b.x) / (2 pi) + 0.5        v = atan2(b.z, hypot(b.x, b.y)) / pi + 0.5
// with (u, v) in [0, 1]^2 and v = 0 at the image's bottom. The EXR stores row 0 at the top
// and Blender samples texel (i, j) at its centre: u = (i + 0.5) / W, v = 1 - (j + 0.5) / H.
//
// The project (core/latlong.h): longitude = atan2(d.x, d.z), latitude = asin(d.y), node
// (x, y) at x / (W - 1) = 0.5 - longitude / (2 pi), y / (H - 1) = 0.5 - latitude / pi.
//
// With d = (b.y, b.z, b.x) the longitude is atan2(b.y, b.x), so x / (W - 1) = u and
// y / (H - 1) = 1 - v: the picture maps onto ours without any flip or shift. The map
// (x, y, z)_blender -> (y, z, x)_project is a proper rotation (a cyclic axis permutation,
// det +1: 120 deg about (1, 1, 1) / sqrt 3), so nothing is mirrored: Blender +X (image
// centre) -> project +Z (longitude 0, image centre); Blender +Y (left quarter) -> +X
// (longitude +90 deg); Blender +Z (up) -> +Y. Only the sample positions differ (texel
// centres vs nodes), hence the bilinear resampling: node x sits at source column
// x W / (W - 1) - 0.5 (wrapping), node y at source row y H / (H - 1) - 0.5 (clamped).

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

// Continuous source pixel position (column, row) of a project direction.
std::array<double, 2> SourcePosition(const latlong::Vec3d& d, SourceConvention c, int w, int h) {
  if (c == SourceConvention::kExr) return latlong::PixelPosition(d, w, h);
  // Project -> Blender: the inverse of (x, y, z)_b -> (y, z, x)_p is (x, y, z)_p -> (z, x, y)_b.
  const double bx = d[2], by = d[0], bz = d[1];
  const double u = -std::atan2(by, bx) / (2.0 * kPi) + 0.5;
  const double v = std::atan2(bz, std::hypot(bx, by)) / kPi + 0.5;
  return {u * w - 0.5, (1.0 - v) * h - 0.5};
}

// Snaps a coordinate that is an integer up to rounding, so that a same-size exr -> exr
// copy is exact and a NaN neighbour with a zero weight cannot leak in (0 * NaN = NaN).
double Snap(double t) {
  const double r = std::round(t);
  return std::abs(t - r) < 1e-9 ? r : t;
}

}  // namespace

SourceConvention ParseSourceConvention(const std::string& text, const std::string& option) {
  if (text == "blender") return SourceConvention::kBlender;
  if (text == "exr") return SourceConvention::kExr;
  throw Error(option + ": unknown convention '" + text + "' (expected blender or exr)");
}

const char* ToString(SourceConvention c) { return c == SourceConvention::kBlender ? "blender" : "exr"; }

std::array<double, 3> BlenderToProjectDirection(const std::array<double, 3>& b) { return {b[1], b[2], b[0]}; }

ImageRGB ResampleToProjectLatLong(const ImageRGB& src, SourceConvention convention, int out_w, int out_h) {
  ImageRGB out(out_w, out_h);
  const int sw = src.width, sh = src.height;
  // Longitude period in source columns: Blender's texels tile [0, 1) once; the exr
  // convention stores the seam twice (column sw - 1 repeats column 0).
  const int period = convention == SourceConvention::kBlender ? sw : sw - 1;
  auto wrap = [period](long long i) { return static_cast<int>(((i % period) + period) % period); };
  for (int y = 0; y < out_h; ++y) {
    for (int x = 0; x < out_w; ++x) {
      const auto d = latlong::PixelDirection(x, y, out_w, out_h);
      const auto p = SourcePosition(d, convention, sw, sh);
      const double sx = Snap(p[0]), sy = std::clamp(Snap(p[1]), 0.0, static_cast<double>(sh - 1));
      const double fx = std::floor(sx), fy = std::floor(sy);
      const double tx = sx - fx, ty = sy - fy;
      const int x0 = wrap(static_cast<long long>(fx)), x1 = wrap(static_cast<long long>(fx) + 1);
      const int y0 = static_cast<int>(fy), y1 = std::min(y0 + 1, sh - 1);
      const double wts[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
      const int xs[4] = {x0, x1, x0, x1}, ys[4] = {y0, y0, y1, y1};
      for (int c = 0; c < 3; ++c) {
        double acc = 0.0;
        for (int k = 0; k < 4; ++k) {
          if (wts[k] != 0.0) acc += wts[k] * src.at(xs[k], ys[k], c);
        }
        out.at(x, y, c) = static_cast<float>(acc);
      }
    }
  }
  // A pole row is a single direction: give it one radiance, the mean of its finite samples.
  for (int y : {0, out_h - 1}) {
    for (int c = 0; c < 3; ++c) {
      double sum = 0.0;
      int n = 0;
      for (int x = 0; x < out_w; ++x) {
        const float v = out.at(x, y, c);
        if (std::isfinite(v)) {
          sum += v;
          ++n;
        }
      }
      const float mean = n ? static_cast<float>(sum / n) : std::numeric_limits<float>::quiet_NaN();
      for (int x = 0; x < out_w; ++x) out.at(x, y, c) = mean;
    }
  }
  return out;
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
