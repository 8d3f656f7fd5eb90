// Exposure settings in a photo's EXIF block (JPEG, TIFF, PNG, DNG and camera raw files).
#pragma once
#include <cmath>
#include <string>

namespace skycal::capture {

struct ExifExposure {
  double exposure_time_s = NAN;  // Exif.Photo.ExposureTime (else 2^-ShutterSpeedValue); NAN: absent
  double f_number = NAN;         // Exif.Photo.FNumber (else 2^(ApertureValue/2)); NAN: absent
  double iso = NAN;              // Exif.Photo.ISOSpeedRatings; NAN: absent
  bool has_exif = false;         // the file carries an EXIF block at all
  std::string error;             // why nothing could be read (unsupported format, corrupt block), else ""
};

// Never throws for a file without EXIF or of a format the library does not know: the
// fields stay NAN and `error` says why. Throws skycal::Error naming the file only when it
// does not exist.
ExifExposure ReadExifExposure(const std::string& path);

// Writes ExposureTime, FNumber and ISOSpeedRatings (fields that are NAN are left out) into
// the file's EXIF block, in place, keeping the rest of its metadata. For tests and tools
// that tag brackets; throws skycal::Error naming the file on failure.
void WriteExifExposure(const std::string& path, const ExifExposure& exposure);

}  // namespace skycal::capture
