// EXIF through exiv2 (Debian libexiv2-dev, 0.27). Why exiv2 rather than libexif (the
// other maintained choice in Debian): brackets arrive as camera JPEGs, 16-bit TIFFs from a
// raw developer, PNGs or the raw files themselves (CR2, NEF, ARW, DNG), and exiv2 reads
// EXIF from all of them with one call, and writes it too (the tests tag their synthetic
// brackets through the same library), while libexif only parses JPEG APP1 blocks and cannot
// insert one into a file. exiv2 is actively maintained upstream (0.28 in newer Debian) and
// in Debian (security updates on bookworm).
#include "skycal/capture/exif_exposure.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <numeric>
#include <utility>

#include "exiv2_read.h"
#include "skycal/core/error.h"

// exiv2 0.27's API hands out std::auto_ptr (deprecated since C++11, still in libstdc++).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>

namespace skycal::capture {
namespace {

// Exposure times as cameras write them (1/250, 1/3, 2, 2.5): 1/n when 1/t is an integer
// to within 1e-4, else a fraction over 10^6.
Exiv2::URational ToRational(double v) {
  if (v > 0.0 && v < 1.0) {
    const double n = std::round(1.0 / v);
    if (std::fabs(n * v - 1.0) < 1e-4) return {1u, static_cast<uint32_t>(n)};
  }
  uint64_t num = static_cast<uint64_t>(std::llround(v * 1e6)), den = 1000000;
  const uint64_t g = std::gcd(num, den);
  if (g > 1) num /= g, den /= g;
  while (num > 0xffffffffull) num /= 10, den /= 10;  // huge values: lose precision, keep the ratio
  return {static_cast<uint32_t>(num), static_cast<uint32_t>(std::max<uint64_t>(den, 1))};
}

}  // namespace

ExifExposure ReadExifExposure(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path + ": no such file (reading EXIF exposure)");
  ExifExposure e;
  try {
    auto image = OpenExif(path);
    const Exiv2::ExifData& exif = image->exifData();
    e.has_exif = !exif.empty();
    if (!e.has_exif) {
      e.error = "no EXIF block";
      return e;
    }
    e.exposure_time_s = ExifNumber(exif, "Exif.Photo.ExposureTime");
    if (!std::isfinite(e.exposure_time_s)) e.exposure_time_s = ExifNumber(exif, "Exif.Image.ExposureTime");  // TIFF/EP
    if (!std::isfinite(e.exposure_time_s)) {
      const double tv = ExifNumber(exif, "Exif.Photo.ShutterSpeedValue");  // APEX
      if (std::isfinite(tv)) e.exposure_time_s = std::exp2(-tv);
    }
    e.f_number = ExifNumber(exif, "Exif.Photo.FNumber");
    if (!std::isfinite(e.f_number)) e.f_number = ExifNumber(exif, "Exif.Image.FNumber");
    if (!std::isfinite(e.f_number)) {
      const double av = ExifNumber(exif, "Exif.Photo.ApertureValue");  // APEX
      if (std::isfinite(av)) e.f_number = std::exp2(av / 2.0);
    }
    e.iso = ExifNumber(exif, "Exif.Photo.ISOSpeedRatings");
    if (!std::isfinite(e.iso)) e.iso = ExifNumber(exif, "Exif.Image.ISOSpeedRatings");
    // A 0 (or negative) field is a camera's "unknown", not a value.
    for (double* v : {&e.exposure_time_s, &e.f_number, &e.iso})
      if (!(*v > 0.0)) *v = NAN;
  } catch (const Exiv2::AnyError& err) {
    e.error = std::string("exiv2: ") + err.what();
  } catch (const std::exception& err) {
    e.error = err.what();
  }
  return e;
}

void WriteExifExposure(const std::string& path, const ExifExposure& exposure) {
  try {
    auto image = OpenExif(path);
    Exiv2::ExifData exif = image->exifData();
    if (std::isfinite(exposure.exposure_time_s)) exif["Exif.Photo.ExposureTime"] = ToRational(exposure.exposure_time_s);
    if (std::isfinite(exposure.f_number)) exif["Exif.Photo.FNumber"] = ToRational(exposure.f_number);
    if (std::isfinite(exposure.iso)) exif["Exif.Photo.ISOSpeedRatings"] = static_cast<uint16_t>(std::lround(exposure.iso));
    image->setExifData(exif);
    image->writeMetadata();
  } catch (const Exiv2::AnyError& err) {
    throw Error(path + ": cannot write EXIF exposure (exiv2: " + err.what() + ")");
  }
}

}  // namespace skycal::capture

#pragma GCC diagnostic pop
