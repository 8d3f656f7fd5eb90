// When and where a photograph was taken, for the sun's position (solar_position.h): from a
// camera's EXIF (through exiv2) and in an EXR's standard attributes, so that a frame made by
// `capture` from camera brackets carries them to `calibrate`.
//
// EXIF (CIPA DC-008, Exif 2.32): GPSDateStamp + GPSTimeStamp are UTC; DateTimeOriginal is
// local time, with its UTC offset in OffsetTimeOriginal ("+02:00", Exif 2.31) when the camera
// writes one; GPSLatitude/GPSLongitude are degrees, minutes, seconds with N/S and E/W refs.
// OpenEXR's standard attributes (ImfStandardAttributes.h): capDate "YYYY:MM:DD HH:MM:SS"
// local time, utcOffset seconds with UTC = local + utcOffset, latitude (degrees north),
// longitude (degrees east), altitude (metres above sea level).
#pragma once
#include <optional>
#include <string>

#include "skycal/capture/solar_position.h"
#include "skycal/core/exr_io.h"

namespace skycal::capture {

struct TimePlace {
  // ISO 8601 with its UTC offset ("2026-06-21T06:30:00+02:00"): empty when the time is not
  // known, or known only as local time without an offset (then `why_no_time` says so).
  std::string time_iso8601;
  std::optional<double> latitude_deg, longitude_deg, altitude_m;
  std::string source;       // where it came from ("EXIF GPS time stamp", "EXR capDate + utcOffset", ...)
  std::string why_no_time;  // e.g. "DateTimeOriginal without OffsetTimeOriginal: local time of an unknown zone"
  // Time and place both known: the sun's position can be computed.
  bool complete() const { return !time_iso8601.empty() && latitude_deg && longitude_deg; }
};

// The photo's EXIF time and place (exiv2: JPEG, TIFF, PNG, DNG and camera raw files). A file
// without EXIF, or without these tags, gives an empty TimePlace with the reason in
// why_no_time; an unreadable file throws skycal::Error naming it.
TimePlace ReadExifTimePlace(const std::string& path);

// Writes the time (as DateTimeOriginal, with OffsetTimeOriginal when it has an offset) and the
// place (GPS tags) into an image file's EXIF (the tests tag their synthetic photos so).
// Throws skycal::Error naming the file.
void WriteExifTimePlace(const std::string& path, const TimePlace& t);

// The EXR standard attributes' time and place (capDate, utcOffset, latitude, longitude,
// altitude); empty when absent. Throws skycal::Error naming `path` and the attribute when
// one is malformed (a capDate that is not "YYYY:MM:DD HH:MM:SS", a latitude beyond 90).
TimePlace TimePlaceFromExrAttributes(const ExrAttributes& a, const std::string& path);

// The time and place of an SPA input (its local time and UTC offset, latitude, longitude,
// elevation), as a TimePlace.
TimePlace TimePlaceOf(const SpaInput& in, const std::string& source);

// Sets those attributes from `t` (capDate and utcOffset only with a time; each coordinate only
// when known).
void AddTimePlaceAttributes(const TimePlace& t, ExrAttributes* a);

}  // namespace skycal::capture
