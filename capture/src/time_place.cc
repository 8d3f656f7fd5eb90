// A photo's time and place (time_place.h): EXIF through exiv2 (why exiv2: exif_exposure.cc),
// EXR standard attributes through core/exr_io.
#include "skycal/capture/time_place.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>

#include "exiv2_read.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"

// exiv2 0.27's API hands out std::auto_ptr (deprecated since C++11, still in libstdc++).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>

namespace skycal::capture {
namespace {

struct DateTime {
  int year = 0, month = 0, day = 0, hour = 0, minute = 0;
  double second = 0.0;
};

// "YYYY:MM:DD HH:MM:SS" (EXIF's and OpenEXR's capDate form); nullopt otherwise.
std::optional<DateTime> ParseColonDateTime(const std::string& s) {
  DateTime t;
  char tail = 0;
  if (std::sscanf(s.c_str(), "%4d:%2d:%2d %2d:%2d:%lf%c", &t.year, &t.month, &t.day, &t.hour, &t.minute, &t.second, &tail) != 6)
    return std::nullopt;
  if (t.month < 1 || t.month > 12 || t.day < 1 || t.day > 31 || t.hour < 0 || t.hour > 23 || t.minute < 0 || t.minute > 59 ||
      !(t.second >= 0.0 && t.second < 61.0))
    return std::nullopt;
  return t;
}

// "+HH:MM" / "-HH:MM" (EXIF OffsetTime*): minutes east of UTC.
std::optional<int> ParseOffsetMinutes(const std::string& s) {
  int h = 0, m = 0;
  char sign = 0, tail = 0;
  if (std::sscanf(s.c_str(), "%c%2d:%2d%c", &sign, &h, &m, &tail) != 3 || (sign != '+' && sign != '-') || h > 18 || m > 59)
    return std::nullopt;
  return (sign == '-' ? -1 : 1) * (60 * h + m);
}

std::string Iso8601(const DateTime& t, int offset_minutes) {
  char buf[64];
  const int a = std::abs(offset_minutes);
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d%c%02d:%02d", t.year, t.month, t.day, t.hour, t.minute,
                static_cast<int>(std::floor(t.second)), offset_minutes < 0 ? '-' : '+', a / 60, a % 60);
  return buf;
}

// An ISO 8601 time as Iso8601 writes it; *offset_minutes unset when it has no offset (a
// local time of an unknown zone).
std::optional<DateTime> ParseIsoBack(const std::string& iso, std::optional<int>* offset_minutes) {
  DateTime t;
  char sign = 0;
  int oh = 0, om = 0;
  const int n = std::sscanf(iso.c_str(), "%4d-%2d-%2dT%2d:%2d:%lf%c%2d:%2d", &t.year, &t.month, &t.day, &t.hour, &t.minute,
                            &t.second, &sign, &oh, &om);
  if (n != 6 && n != 9) return std::nullopt;
  if (n == 9) *offset_minutes = (sign == '-' ? -1 : 1) * (60 * oh + om);
  return t;
}

std::string ColonDateTime(const DateTime& d) {
  char local[32];
  std::snprintf(local, sizeof local, "%04d:%02d:%02d %02d:%02d:%02d", d.year, d.month, d.day, d.hour, d.minute,
                static_cast<int>(d.second));
  return local;
}

// Degrees from EXIF's three rationals (degrees, minutes, seconds) and its N/S or E/W ref.
std::optional<double> GpsDegrees(const Exiv2::ExifData& exif, const char* key, const char* ref_key, char negative) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  if (it == exif.end() || it->count() < 3) return std::nullopt;
  double deg = 0.0;
  for (long i = 0; i < 3; ++i) {
    const Exiv2::Rational r = it->toRational(i);
    if (r.second == 0) return std::nullopt;
    deg += static_cast<double>(r.first) / r.second / std::pow(60.0, static_cast<double>(i));
  }
  const auto ref = ExifText(exif, ref_key);
  return ref && !ref->empty() && (*ref)[0] == negative ? -deg : deg;
}

// The time: the GPS UTC stamps, else DateTimeOriginal with OffsetTimeOriginal.
void ExifTime(const Exiv2::ExifData& exif, TimePlace* t) {
  const auto gps_date = ExifText(exif, "Exif.GPSInfo.GPSDateStamp");
  const auto gps_time = exif.findKey(Exiv2::ExifKey("Exif.GPSInfo.GPSTimeStamp"));
  if (gps_date && gps_time != exif.end() && gps_time->count() >= 3) {
    double hms[3];
    bool ok = true;
    for (long i = 0; i < 3; ++i) {
      const Exiv2::Rational r = gps_time->toRational(i);
      ok = ok && r.second != 0;
      hms[i] = ok ? static_cast<double>(r.first) / r.second : 0.0;
    }
    if (auto d = ParseColonDateTime(*gps_date + " 00:00:00"); d && ok) {
      d->hour = static_cast<int>(hms[0]), d->minute = static_cast<int>(hms[1]), d->second = hms[2];
      t->time_iso8601 = Iso8601(*d, 0);
      t->source = "EXIF GPS time stamp (UTC)";
      return;
    }
  }
  const auto local = ExifText(exif, "Exif.Photo.DateTimeOriginal");
  if (!local) {
    t->why_no_time = "no DateTimeOriginal or GPS time stamp in the EXIF";
    return;
  }
  const auto d = ParseColonDateTime(*local);
  const auto offset = ExifText(exif, "Exif.Photo.OffsetTimeOriginal");
  const auto minutes = offset ? ParseOffsetMinutes(*offset) : std::nullopt;
  if (!d) t->why_no_time = "DateTimeOriginal '" + *local + "' is not YYYY:MM:DD HH:MM:SS";
  else if (!minutes) t->why_no_time = "DateTimeOriginal without OffsetTimeOriginal: the local time of an unknown zone";
  else {
    t->time_iso8601 = Iso8601(*d, *minutes);
    t->source = "EXIF DateTimeOriginal + OffsetTimeOriginal";
  }
}

}  // namespace

TimePlace ReadExifTimePlace(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path + ": no such file (reading EXIF time and place)");
  TimePlace t;
  try {
    auto image = OpenExif(path);
    const Exiv2::ExifData& exif = image->exifData();
    if (exif.empty()) {
      t.why_no_time = "no EXIF block";
      return t;
    }
    ExifTime(exif, &t);
    t.latitude_deg = GpsDegrees(exif, "Exif.GPSInfo.GPSLatitude", "Exif.GPSInfo.GPSLatitudeRef", 'S');
    t.longitude_deg = GpsDegrees(exif, "Exif.GPSInfo.GPSLongitude", "Exif.GPSInfo.GPSLongitudeRef", 'W');
    const auto alt = exif.findKey(Exiv2::ExifKey("Exif.GPSInfo.GPSAltitude"));
    if (alt != exif.end() && alt->count() > 0 && alt->toRational(0).second != 0) {
      const auto below = ExifText(exif, "Exif.GPSInfo.GPSAltitudeRef");  // 1: below sea level
      const double m = static_cast<double>(alt->toRational(0).first) / alt->toRational(0).second;
      t.altitude_m = below && *below == "1" ? -m : m;
    }
  } catch (const Exiv2::AnyError& e) {
    throw Error(path + ": cannot read EXIF (exiv2: " + e.what() + ")");
  }
  return t;
}

namespace {

Exiv2::URational Rational(double v, uint32_t den) { return {static_cast<uint32_t>(std::llround(v * den)), den}; }

std::string Dms(double deg) {  // three rationals: degrees, minutes, 1/1000 seconds
  deg = std::fabs(deg);
  const double d = std::floor(deg), m = std::floor((deg - d) * 60.0), s = ((deg - d) * 60.0 - m) * 60.0;
  return std::to_string(static_cast<int>(d)) + "/1 " + std::to_string(static_cast<int>(m)) + "/1 " +
         std::to_string(std::llround(s * 1000.0)) + "/1000";
}

}  // namespace

void WriteExifTimePlace(const std::string& path, const TimePlace& t) {
  try {
    auto image = OpenExif(path);
    Exiv2::ExifData exif = image->exifData();
    std::optional<int> offset;
    if (const auto d = ParseIsoBack(t.time_iso8601, &offset)) {
      exif["Exif.Photo.DateTimeOriginal"] = ColonDateTime(*d);
      if (offset) exif["Exif.Photo.OffsetTimeOriginal"] = t.time_iso8601.substr(t.time_iso8601.size() - 6);
    }
    if (t.latitude_deg) {
      Exiv2::Value::AutoPtr v = Exiv2::Value::create(Exiv2::unsignedRational);
      v->read(Dms(*t.latitude_deg));
      exif.add(Exiv2::ExifKey("Exif.GPSInfo.GPSLatitude"), v.get());
      exif["Exif.GPSInfo.GPSLatitudeRef"] = std::string(*t.latitude_deg < 0 ? "S" : "N");
    }
    if (t.longitude_deg) {
      Exiv2::Value::AutoPtr v = Exiv2::Value::create(Exiv2::unsignedRational);
      v->read(Dms(*t.longitude_deg));
      exif.add(Exiv2::ExifKey("Exif.GPSInfo.GPSLongitude"), v.get());
      exif["Exif.GPSInfo.GPSLongitudeRef"] = std::string(*t.longitude_deg < 0 ? "W" : "E");
    }
    if (t.altitude_m) exif["Exif.GPSInfo.GPSAltitude"] = Rational(std::fabs(*t.altitude_m), 100);
    image->setExifData(exif);
    image->writeMetadata();
  } catch (const Exiv2::AnyError& e) {
    throw Error(path + ": cannot write EXIF time and place (exiv2: " + e.what() + ")");
  }
}

TimePlace TimePlaceFromExrAttributes(const ExrAttributes& a, const std::string& path) {
  TimePlace t;
  auto coordinate = [&](const char* name, double limit) -> std::optional<double> {
    const auto it = a.floats.find(name);
    if (it == a.floats.end()) return std::nullopt;
    if (!(std::fabs(it->second) <= limit))
      throw Error(path + ": attribute '" + name + "' = " + FormatNumber(it->second) + " (expected degrees in [-" +
                  FormatNumber(limit) + ", " + FormatNumber(limit) + "])");
    return it->second;
  };
  t.latitude_deg = coordinate("latitude", 90.0);
  t.longitude_deg = coordinate("longitude", 180.0);
  if (const auto alt = a.floats.find("altitude"); alt != a.floats.end() && std::isfinite(alt->second)) t.altitude_m = alt->second;
  const auto date = a.strings.find("capDate");
  if (date == a.strings.end()) {
    t.why_no_time = "no capDate attribute";
    return t;
  }
  const auto d = ParseColonDateTime(date->second);
  if (!d) throw Error(path + ": attribute 'capDate' = '" + date->second + "' (expected \"YYYY:MM:DD HH:MM:SS\", local time)");
  const auto utc = a.floats.find("utcOffset");
  if (utc == a.floats.end()) {
    t.why_no_time = "capDate without utcOffset: the local time of an unknown zone";
    return t;
  }
  if (!(std::fabs(utc->second) <= 18.0 * 3600.0))
    throw Error(path + ": attribute 'utcOffset' = " + FormatNumber(utc->second) + " (expected seconds in [-64800, 64800])");
  t.time_iso8601 = Iso8601(*d, static_cast<int>(std::lround(-utc->second / 60.0)));  // UTC = local + utcOffset
  t.source = "EXR capDate + utcOffset";
  return t;
}

TimePlace TimePlaceOf(const SpaInput& in, const std::string& source) {
  DateTime d;
  d.year = in.year, d.month = in.month, d.day = in.day, d.hour = in.hour, d.minute = in.minute, d.second = in.second;
  TimePlace t;
  t.time_iso8601 = Iso8601(d, static_cast<int>(std::lround(in.timezone_h * 60.0)));
  t.latitude_deg = in.latitude_deg;
  t.longitude_deg = in.longitude_deg;
  t.altitude_m = in.elevation_m;
  t.source = source;
  return t;
}

void AddTimePlaceAttributes(const TimePlace& t, ExrAttributes* a) {
  std::optional<int> offset;
  if (const auto d = ParseIsoBack(t.time_iso8601, &offset); d && offset) {
    a->strings["capDate"] = ColonDateTime(*d);
    a->floats["utcOffset"] = static_cast<float>(-60.0 * *offset);
  }
  if (t.latitude_deg) a->floats["latitude"] = static_cast<float>(*t.latitude_deg);
  if (t.longitude_deg) a->floats["longitude"] = static_cast<float>(*t.longitude_deg);
  if (t.altitude_m) a->floats["altitude"] = static_cast<float>(*t.altitude_m);
}

}  // namespace skycal::capture

#pragma GCC diagnostic pop
