// Display previews: exposure, sanitising, OCIO display/view transform, 8-bit quantising.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "exposure.h"
#include "ocio_config.h"
#include "skycal/color/preview.h"
#include "skycal/core/error.h"

namespace skycal::color {
namespace {

// |ev| above this is a typo, not a preview: 2^64 already spans any real sky's range, and
// the bound keeps 2^ev finite in float.
constexpr double kMaxAbsEv = 64.0;

std::string FormatDouble(double v, const char* fmt = "%.4g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// Encoded display value in [0, 1] -> 8-bit code value. NaN (defensive: OCIO should not
// produce one from sanitised input) becomes 0.
uint8_t Quantize8(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 255;
  return static_cast<uint8_t>(std::lround(v * 255.0f));
}

}  // namespace

bool PreviewOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (input_colorspace.empty()) return fail("input_colorspace is empty: expected a colour space name");
  if (display.empty()) return fail("display is empty: expected a display name such as 'sRGB'");
  if (!std::isnan(exposure_ev) && !(std::fabs(exposure_ev) <= kMaxAbsEv)) {
    return fail("exposure_ev is " + FormatDouble(exposure_ev) + ": expected NaN (automatic) or a value in [-" +
                FormatDouble(kMaxAbsEv) + ", " + FormatDouble(kMaxAbsEv) + "] stops");
  }
  return true;
}

std::vector<uint8_t> ToDisplay8(const ImageRGB& linear, const PreviewOptions& options, PreviewReport* report) {
  std::string why;
  if (!options.IsValid(&why)) throw Error("preview options: " + why);
  detail::RequireWellFormed(linear, "preview");

  const detail::LoadedConfig cfg = detail::LoadConfig(options.config_path);
  detail::RequireColorSpace(cfg, options.input_colorspace, "input");
  const std::string view = detail::ResolveView(cfg, options.display, options.view);
  const std::string what = "OCIO config '" + cfg.path + "': transform '" + options.input_colorspace +
                           "' -> display '" + options.display + "', view '" + view + "'";

  PreviewReport local;
  PreviewReport& rep = report != nullptr ? *report : local;
  rep = PreviewReport{};
  rep.config_path = cfg.path;
  rep.view = view;

  // Exposure, in the input's linear space, before the view transform.
  rep.exposure_ev = options.exposure_ev;
  if (std::isnan(options.exposure_ev)) {
    const detail::AutoExposure ae = detail::ComputeAutoExposure(linear);
    rep.auto_exposure = true;
    rep.exposure_ev = ae.ev;
    if (ae.pixels_used == 0) {
      rep.notes.push_back("automatic exposure: no finite positive pixels, using 0 EV");
    } else {
      rep.notes.push_back("automatic exposure: log-average luminance " + FormatDouble(ae.log_average) + " over " +
                          std::to_string(ae.pixels_used) + " finite positive pixels mapped to " +
                          FormatDouble(detail::kMidGrey) + " -> " + FormatDouble(ae.ev, "%+.2f") + " EV");
    }
  }
  ImageRGB work = linear;  // the caller's image stays untouched
  const size_t bad = detail::ExposeAndSanitize(work, static_cast<float>(std::exp2(rep.exposure_ev)));
  if (bad > 0) {
    rep.notes.push_back(std::to_string(bad) + " NaN, infinite or negative values replaced " +
                        "(NaN/negative -> 0, +Inf -> bright)");
  }

  try {
    const auto processor = cfg.config->getProcessor(options.input_colorspace.c_str(), options.display.c_str(),
                                                    view.c_str(), OCIO_NAMESPACE::TRANSFORM_DIR_FORWARD);
    detail::ApplyInPlace(processor, work);
  } catch (const OCIO_NAMESPACE::Exception& e) {
    throw Error(what + ": " + e.what());
  }

  std::vector<uint8_t> out(work.pixels.size());
  std::transform(work.pixels.begin(), work.pixels.end(), out.begin(), Quantize8);
  return out;
}

}  // namespace skycal::color
