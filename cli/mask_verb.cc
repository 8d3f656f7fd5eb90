#include "mask_verb.h"

#include <chrono>
#include <cmath>

#include "command_line.h"
#include "finite_output.h"
#include "option_values.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "verb_common.h"

namespace skycal::cli {
namespace {

bool EndsWithExr(const std::string& s) { return s.size() > 4 && s.compare(s.size() - 4, 4, ".exr") == 0; }

}  // namespace

bool MaskOptions::IsValid(std::string* why) const {
  if (reference_path.empty()) {
    *why = "--reference R.exr is required";
    return false;
  }
  if (!EndsWithExr(out_path)) {
    *why = "--out: expected an output path ending in .exr";
    return false;
  }
  if (segmentation.IsValid(why)) return true;
  // The library names SkyMaskOptions' fields; the user set them with these flags.
  static const FieldFlag kFlags[] = {{"SkyMaskOptions::horizon_deg", "--horizon-deg"},
                                     {"SkyMaskOptions::darkness_threshold", "--darkness"},
                                     {"SkyMaskOptions::texture_threshold", "--texture"},
                                     {"SkyMaskOptions::ground_band_deg", "--ground-band-deg"},
                                     {"SkyMaskOptions::ground_dark_share", "--ground-dark-share"},
                                     {"SkyMaskOptions::line_darkness", "--lines"},
                                     {"SkyMaskOptions::dilate_px", "--dilate"}};
  *why = FieldsAsFlags(*why, kFlags);
  return false;
}

nlohmann::json RunMaskImpl(const MaskOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  RefuseOutputsOverInputs({{"--out", o.out_path}}, {{"--reference", o.reference_path}});
  { AtomicOutput probe(o.out_path); }  // fail on an unwritable output before the work
  const capture::LatLongFrame frame = capture::ReadLatLongFrame(o.reference_path);
  RequireValidShare(o.reference_path, frame.radiance);
  Log("mask", "segmenting " + o.reference_path + " (" + std::to_string(frame.radiance.width) + "x" +
                  std::to_string(frame.radiance.height) + (frame.sun_direction ? ", sun known" : ", no sun direction") + ")");
  const capture::SkyMask m = capture::EstimateSkyMask(frame.radiance, frame.sun_direction, o.segmentation);
  ImageRGB rgb(m.width, m.height);
  for (size_t i = 0; i < m.sky.size(); ++i) rgb.pixels[3 * i] = rgb.pixels[3 * i + 1] = rgb.pixels[3 * i + 2] = m.sky[i];
  ExrAttributes attributes;
  attributes.strings["skycalMaskSource"] = "skycal mask (automatic sky segmentation) of " + o.reference_path;
  WriteExrRGBWithPlanes(o.out_path, rgb, {{"confidence", m.confidence}}, attributes, ExrPixelType::kHalf);
  const double share = m.above_horizon ? static_cast<double>(m.non_sky_above_horizon) / m.above_horizon : 0.0;
  Log("mask", "wrote " + o.out_path + ": " + std::to_string(m.non_sky_above_horizon) + " pixels above the horizon are not sky (" +
                  std::to_string(std::lround(100.0 * share)) + "%)");
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return {{"reference", o.reference_path},
          {"out", o.out_path},
          {"size", {m.width, m.height}},
          {"above_horizon_pixels", m.above_horizon},
          {"non_sky_above_horizon_pixels", m.non_sky_above_horizon},
          {"non_sky_above_horizon_fraction", share},
          {"ground_connected_candidates", m.ground_connected_candidates},
          {"floating_candidates_dropped", m.floating_candidates},
          {"sun_known", frame.sun_direction.has_value()},
          {"time_ms", ms}};
}

MaskOptions ParseMaskArgs(int argc, char** argv) {
  VerbCommandLine cl("mask", "skycal mask: find what is not sky in a reference frame (no hand drawing)",
                     "  skycal mask --reference FRAME.exr --out MASK.exr [--horizon-deg D] [--no-grabcut] [--json]",
                     "MASK.exr: R = G = B = 1 sky, 0 not sky (what `skycal fit --mask` reads: R < 0.5 excludes),\n"
                     "channel `confidence` in [0, 1]. Everything at or below --horizon-deg is not sky.");
  MaskOptions o;
  bool json = false, no_grabcut = false;
  auto& s = o.segmentation;
  cl.Text("--reference", &o.reference_path, "FRAME.exr", "lat-long reference frame (required; its sunDirection is used)");
  cl.Text("--out", &o.out_path, "MASK.exr", "output mask (required)");
  cl.Number("--horizon-deg", &s.horizon_deg, "DEG", "elevation at and below which nothing is sky (default 0, [-10, 30])");
  cl.Number("--darkness", &s.darkness_threshold, "LOG",
            "natural-log units below the sky's reference luminance that make a non-sky candidate (default 0.7)");
  cl.Number("--texture", &s.texture_threshold, "LOG",
            "local RMS of log luminance that marks texture (foliage, lattice; default 0.06)");
  cl.Number("--ground-band-deg", &s.ground_band_deg, "DEG",
            "candidates count only when connected to this band above the horizon (default 1)");
  cl.Number("--ground-dark-share", &s.ground_dark_share, "F",
            "... and when this share of their pixels in that band is dark (by --darkness): a cloud bank meeting the "
            "horizon through haze is not ground (default 0.1, [0, 1]; 0: any contact)");
  cl.Number("--lines", &s.line_darkness, "LOG",
            "thin dark lines (wires, a crane's jib) this much darker than their 3x3 closing join the non-sky "
            "class they hang from (default 0.05, [0, 10]; 0: off)");
  cl.Integer("--dilate", &s.dilate_px, 0, 16, "expected an integer in [0, 16] pixels", "PX",
             "grow the non-sky class by this many pixels (default 1)");
  cl.Flag("--no-grabcut", &no_grabcut, "skip the cv::grabCut refinement (cues and ground connection only)");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  if (no_grabcut) s.grabcut = false;
  return o;
}

int RunMask(int argc, char** argv) {
  return RunVerb("mask", WantsJson(argc, argv), [&]() { return RunMaskImpl(ParseMaskArgs(argc, argv)); });
}

}  // namespace skycal::cli
