// exiv2 reading shared by the capture library's EXIF readers and writers (exif_exposure.cc,
// lens_profile.cc, time_place.cc): a file opened with its metadata read and exiv2's own
// logging muted once, and a datum by key as text or as a number.
#pragma once
#include <cmath>
#include <mutex>
#include <optional>
#include <string>

// exiv2 0.27's API hands out std::auto_ptr (deprecated since C++11, still in libstdc++).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>
#pragma GCC diagnostic pop

namespace skycal::capture {

// exiv2 logs warnings (e.g. "no EXIF block") to stderr by default; the readers report them.
inline void QuietExiv2() {
  static std::once_flag once;
  std::call_once(once, [] { Exiv2::LogMsg::setLevel(Exiv2::LogMsg::mute); });
}

// The file opened by exiv2 (its logging muted) with its metadata read; exiv2's errors
// (Exiv2::AnyError, a std::exception) propagate to the caller, which names what it was doing.
inline auto OpenExif(const std::string& path) {
  QuietExiv2();
  auto image = Exiv2::ImageFactory::open(path);
  image->readMetadata();
  return image;
}

// The datum as exiv2 prints it; nullopt when absent or empty.
inline std::optional<std::string> ExifText(const Exiv2::ExifData& exif, const char* key) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  if (it == exif.end() || it->count() == 0) return std::nullopt;
  return it->toString();
}

// The datum's first value as a number (a rational divided out; else its float); NAN when
// absent or not finite.
inline double ExifNumber(const Exiv2::ExifData& exif, const char* key) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  if (it == exif.end() || it->count() == 0) return NAN;
  const Exiv2::Rational r = it->toRational(0);
  const double v = r.second != 0 ? static_cast<double>(r.first) / r.second : it->toFloat(0);
  return std::isfinite(v) ? v : NAN;
}

}  // namespace skycal::capture
