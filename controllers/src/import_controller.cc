#include "skycal/controllers/import_controller.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/finite_pixels.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/radiance_io.h"
#include "skycal/core/sha256.h"
#include "skycal/skysun/find_sun.h"

namespace skycal::controllers {
namespace {

bool Fail(std::string* why, const std::string& text) {
  if (why) *why = text;
  return false;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string Vec3Text(const std::array<double, 3>& v) {
  std::ostringstream s;
  s << v[0] << "," << v[1] << "," << v[2];
  return s.str();
}

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

// The disc, else the sky's luminance pattern (skysun::FindSun), on the converted frame.
void DetectSun(const ImportOptions& o, ImportedPhoto* p) {
  ImportedSun& s = p->sun;
  const auto f = skysun::FindSun(p->frame.radiance, o.min_sun_contrast, skysun::SkySunOptions{}, &s.refusal);
  if (!f) return;
  s.refusal.clear();
  s.direction = f->direction;
  if (f->source == "disc") {
    s.source = SunSource::kDisc;
    s.disc_contrast = f->disc_contrast;
    s.disc_peak_luminance = f->disc_peak_luminance;
    s.disc_region_pixels = f->disc_region_pixels;
    s.disc_clipped = f->disc_clipped;
    if (f->disc_clipped) {
      p->warnings.push_back(o.in_path + ": the sun is clipped (a plateau at " + std::to_string(f->disc_peak_luminance) +
                            "): its disc radiance is unknown; the fit masks the sun cone and clipped pixels");
    }
    return;
  }
  s.source = SunSource::kSkyEstimate;
  s.uncertainty_deg = f->uncertainty_deg;
  s.no_disc = f->disc_refusal;
  s.sky_log_rmse = f->sky->log_rmse;
  s.sky_cie_type = f->sky->sky_type;
  p->frame.extra.floats["skycalSunUncertaintyDeg"] = static_cast<float>(f->uncertainty_deg);
  p->warnings.push_back(o.in_path + ": no sun disc (" + f->disc_refusal +
                        "): the sun is placed from the sky's luminance pattern, uncertain by " +
                        FormatNumber(f->uncertainty_deg) + " deg (docs/capture.md)");
}

// The frame's sun: the option, the detection, or (a source in the project's convention) its
// own sunDirection attribute.
void ImportSun(const ImportOptions& o, const ExrAttributes& source, ImportedPhoto* p) {
  if (o.sun_dir) {
    p->sun.direction = latlong::Normalized(*o.sun_dir, "ImportOptions::sun_dir");
    p->sun.source = SunSource::kOption;
  } else if (o.detect_sun) {
    DetectSun(o, p);
  } else if (p->convention == capture::SourceConvention::kExr) {
    if (auto sun = capture::SunDirectionAttribute(source, o.in_path)) {
      p->sun.direction = *sun;
      p->sun.source = SunSource::kAttribute;
    }
  }
  p->frame.sun_direction = p->sun.direction;
}

// What a readable file that is neither picture is, by its first bytes ("" when unknown).
std::string LowDynamicRangeKind(const std::string& path) {
  const std::string head = LeadingBytes(path, 4);  // empty for a FIFO: left to the OpenEXR reader's refusal
  if (head.starts_with("\xFF\xD8\xFF")) return "a JPEG";
  if (head == "\x89PNG") return "a PNG";
  if (head == std::string("II*\0", 4) || head == std::string("MM\0*", 4)) return "a TIFF";
  return "";
}

// The source picture: a Radiance picture (.hdr: no attributes, so the Blender convention that
// HDR publishers write), else an OpenEXR file. A JPEG, PNG or TIFF is refused with what to do.
ExrRGB ReadSource(const std::string& path, std::vector<std::string>* warnings, std::string* format) {
  if (!IsRadiancePicture(path)) {
    if (const std::string kind = LowDynamicRangeKind(path); !kind.empty())
      throw Error(path + ": " + kind + " image, not an HDR picture (expected a lat-long OpenEXR or Radiance .hdr; " +
                  "exposure brackets are merged by `skycal capture`)");
    *format = "OpenEXR";
    return ReadExrRGB(path);
  }
  RadiancePicture pic = ReadRadiancePicture(path);
  *format = "Radiance RGBE (" + pic.header.resolution + ", EXPOSURE " + FormatNumber(pic.header.exposure) +
            " divided out)";
  warnings->insert(warnings->end(), pic.warnings.begin(), pic.warnings.end());
  ExrRGB src;
  src.image = std::move(pic.image);
  src.channels = {"R", "G", "B"};
  return src;
}

}  // namespace

const char* ToString(SunSource s) {
  switch (s) {
    case SunSource::kOption: return "option";
    case SunSource::kAttribute: return "attribute";
    case SunSource::kDisc: return "disc";
    case SunSource::kSkyEstimate: return "sky-estimate";
    case SunSource::kNone: break;
  }
  return "none";
}

const char* RecordedName(SunSource s) { return s == SunSource::kDisc ? "detected" : ToString(s); }

bool ImportOptions::IsValid(std::string* why) const {
  if (in_path.empty()) return Fail(why, "ImportOptions::in_path is not set (expected the source picture: OpenEXR or Radiance .hdr)");
  if (!out_path.empty() && !EndsWith(out_path, ".exr"))
    return Fail(why, "ImportOptions::out_path = " + out_path + " (expected a path ending in .exr)");
  if (sun_dir && detect_sun)
    return Fail(why, "ImportOptions::sun_dir and ImportOptions::detect_sun are both set (expected one, not both)");
  if (sun_dir) {
    const auto& d = *sun_dir;
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!std::isfinite(n) || !(n > 1e-9))
      return Fail(why, "ImportOptions::sun_dir = " + Vec3Text(d) + " (expected a finite, non-zero vector)");
  }
  if (!(min_sun_contrast >= 1.0))
    return Fail(why, "ImportOptions::min_sun_contrast = " + FormatNumber(min_sun_contrast) + " (expected a ratio >= 1)");
  return true;
}

ImportedPhoto ImportPhoto(const ImportOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  ImportedPhoto p;
  std::string format;
  ExrRGB src = ReadSource(o.in_path, &p.warnings, &format);
  RequireValidShare(o.in_path, src.image);
  p.source_sha256 = Sha256OfFile(o.in_path);
  p.source_file = std::filesystem::path(o.in_path).filename().string();
  p.source_channels = src.channels;
  p.source_envmap_latlong = src.attributes.envmap_latlong;
  const int w = src.image.width, h = src.image.height;
  if (w != 2 * h || h < 2) {
    throw Error(o.in_path + ": image is " + std::to_string(w) + "x" + std::to_string(h) +
                ", expected a 2:1 equirectangular panorama (width = 2 x height)");
  }
  p.convention = o.convention ? *o.convention : capture::ChooseConvention(src.attributes);
  if (p.convention == capture::SourceConvention::kBlender && src.attributes.envmap_latlong) {
    p.warnings.push_back(o.in_path + " carries envmap=latlong (the project's convention?) but is read as blender; "
                         "pass ImportOptions::convention = exr if it is already a skycal frame");
  }
  p.source_pixels = Census(src.image);
  p.frame.radiance = capture::ResampleToProjectLatLong(src.image, p.convention, w, h);
  p.frame_pixels = Census(p.frame.radiance);
  const PixelCensus& sc = p.source_pixels;
  if (sc.negative + sc.nan + sc.inf > 0) {
    p.warnings.push_back(o.in_path + ": " + std::to_string(sc.negative) + " negative, " + std::to_string(sc.nan) +
                         " NaN, " + std::to_string(sc.inf) +
                         " Inf pixels (lossy-compression ringing?): non-finite ones written as 0, which the fit masks like negative ones");
  }
  ImportSun(o, src.attributes, &p);
  p.time_place = capture::TimePlaceFromExrAttributes(src.attributes, o.in_path);
  capture::AddTimePlaceAttributes(p.time_place, &p.frame.extra);
  p.frame.extra.strings["skycalSource"] = p.source_file + " sha256:" + p.source_sha256;
  p.frame.extra.strings["skycalSourceConvention"] = capture::ToString(p.convention);
  p.frame.extra.strings["skycalSourceFormat"] = format;
  p.frame.extra.strings["skycalSunSource"] = RecordedName(p.sun.source);
  p.frame.extra.strings["skycalUnits"] = "relative scene-linear Rec.709 (source not calibrated: exposure unknown)";
  p.zeroed = MaskNonFinite(&p.frame.radiance, false).non_finite;
  return p;
}

ImportedFile ImportToFile(const ImportOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (o.out_path.empty()) throw Error("ImportOptions::out_path is not set (expected a path ending in .exr)");
  RefuseOutputsOverInputs({{"ImportOptions::out_path", o.out_path}}, {{"ImportOptions::in_path", o.in_path}});
  { AtomicOutput probe(o.out_path); }  // fail on an unwritable output before reading
  ImportedFile f{ImportPhoto(o), 0};
  if (o.detect_sun && !f.photo.sun.direction)
    throw Error(o.in_path + ": ImportOptions::detect_sun: " + f.photo.sun.refusal + "; nothing written");
  // ImportPhoto already set the non-finite values to 0: this only counts what half clamps.
  if (o.half) f.half_clamped = MaskNonFinite(&f.photo.frame.radiance, true).half_clamped;
  capture::WriteLatLongFrame(o.out_path, f.photo.frame, o.half);
  return f;
}

}  // namespace skycal::controllers
