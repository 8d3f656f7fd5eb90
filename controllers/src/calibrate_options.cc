#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include "skycal/capture/solar_position.h"
#include "skycal/controllers/calibrate.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/radiance_io.h"

namespace skycal::controllers {
namespace {

bool Fail(std::string* why, const std::string& text) {
  if (why) *why = text;
  return false;
}

std::string Value(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The pictures of one folder, sorted by name; the other visible files into *skipped.
std::vector<std::string> PicturesIn(const std::filesystem::path& dir, std::vector<std::string>* skipped) {
  std::vector<std::string> found, other;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::filesystem::path& f = it->path();
    if (f.filename().string().starts_with(".") || !std::filesystem::is_regular_file(f)) continue;
    (IsOpenExrFile(f.string()) || IsRadiancePicture(f.string()) ? found : other).push_back(f.string());
  }
  if (ec) throw Error(dir.string() + ": cannot list the folder (" + ec.message() + ")");
  if (found.empty())
    throw Error(dir.string() + ": no OpenEXR or Radiance picture in the folder (" + std::to_string(other.size()) +
                " other file(s))");
  std::sort(found.begin(), found.end());
  std::sort(other.begin(), other.end());
  if (skipped) skipped->insert(skipped->end(), other.begin(), other.end());
  return found;
}

}  // namespace

std::vector<std::string> ExpandPhotoFolders(const std::vector<std::string>& photos, std::vector<std::string>* skipped) {
  std::vector<std::string> out;
  for (const std::string& p : photos) {
    if (!std::filesystem::is_directory(p)) {
      out.push_back(p);
      continue;
    }
    const std::vector<std::string> in = PicturesIn(p, skipped);
    out.insert(out.end(), in.begin(), in.end());
  }
  return out;
}

bool CalibrateOptions::IsValid(std::string* why) const {
  if (photos.empty()) return Fail(why, "CalibrateOptions::photos is empty (expected at least one lat-long OpenEXR or Radiance picture, or a folder of them)");
  std::set<std::string> stems;
  for (const std::string& p : photos) {
    if (p.empty()) return Fail(why, "CalibrateOptions::photos holds an empty path");
    if (std::filesystem::is_directory(p)) continue;  // its pictures are checked once listed (ExpandPhotoFolders)
    const std::string stem = std::filesystem::path(p).stem().string();
    if (stem.empty() || stem == "game" || stem[0] == '.')
      return Fail(why, "CalibrateOptions::photos = '" + p + "' (expected a file name whose stem names its directory: not empty, not 'game', not hidden)");
    if (!stems.insert(stem).second)
      return Fail(why, "CalibrateOptions::photos: two photos named '" + stem + "' (each is written to DIR/<stem>: expected distinct file names)");
  }
  if (out_dir.empty()) return Fail(why, "CalibrateOptions::out_dir is empty (expected a directory)");
  if (latitude_deg.has_value() != longitude_deg.has_value())
    return Fail(why, "CalibrateOptions::latitude_deg and longitude_deg: one given without the other (expected both or neither)");
  if (latitude_deg && !(std::abs(*latitude_deg) <= 90.0))
    return Fail(why, "CalibrateOptions::latitude_deg = " + Value(*latitude_deg) + " (expected [-90, 90] degrees)");
  if (longitude_deg && !(std::abs(*longitude_deg) <= 180.0))
    return Fail(why, "CalibrateOptions::longitude_deg = " + Value(*longitude_deg) + " (expected [-180, 180] degrees)");
  if (latitude_deg && !time_iso8601)
    return Fail(why, "CalibrateOptions::latitude_deg given without time_iso8601 (expected the time as well: the sun needs both)");
  if (time_iso8601) {  // parsed now, not when the sun is first needed (a photo with a disc never asks)
    try {
      capture::ParseIso8601(*time_iso8601, "CalibrateOptions::time_iso8601");
    } catch (const std::exception& e) {
      return Fail(why, e.what());
    }
  }
  if (time_iso8601 && !latitude_deg)
    return Fail(why, "CalibrateOptions::time_iso8601 given without latitude_deg and longitude_deg (expected the place as well: the sun needs both)");
  if (north_longitude_deg && !(std::abs(*north_longitude_deg) <= 360.0))
    return Fail(why, "CalibrateOptions::north_longitude_deg = " + Value(*north_longitude_deg) + " (expected [-360, 360] degrees)");
  if (north_longitude_deg && !latitude_deg)
    return Fail(why, "CalibrateOptions::north_longitude_deg given without time_iso8601, latitude_deg and longitude_deg (it orients the sun of a time and place)");
  if (sun_elevation_deg.has_value() != sun_azimuth_deg.has_value())
    return Fail(why, "CalibrateOptions::sun_elevation_deg and sun_azimuth_deg: one given without the other (expected both or neither)");
  if (sun_elevation_deg && !(std::abs(*sun_elevation_deg) <= 90.0))
    return Fail(why, "CalibrateOptions::sun_elevation_deg = " + Value(*sun_elevation_deg) + " (expected [-90, 90] degrees)");
  if (sun_azimuth_deg && !(std::abs(*sun_azimuth_deg) <= 360.0))
    return Fail(why, "CalibrateOptions::sun_azimuth_deg = " + Value(*sun_azimuth_deg) + " (expected [-360, 360] degrees)");
  if (time_of_day_h && !(*time_of_day_h >= 0.0 && *time_of_day_h < 24.0))
    return Fail(why, "CalibrateOptions::time_of_day_h = " + Value(*time_of_day_h) + " (expected hours in [0, 24))");
  if (time_of_day_h && time_iso8601)
    return Fail(why, "CalibrateOptions::time_of_day_h and time_iso8601 both given (expected one: the time gives the hour)");
  return true;
}

}  // namespace skycal::controllers
