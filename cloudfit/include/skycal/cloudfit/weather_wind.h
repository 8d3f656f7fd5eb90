// One wind for a day: the weather maps inverted from consecutive time-lapse frames are the
// same clouds moved by the wind (frozen turbulence, as the march itself advects its map and
// its noise by wind x time), so the shift between two frames' maps is the wind times the
// time between them. The shift is measured by phase correlation (Kuglin & Hines 1975;
// OpenCV's cv::phaseCorrelate, sub-texel) on the coverage, which the map's tiling makes
// periodic as the transform assumes. Texels the photo did not constrain carry the map's
// mean constrained coverage (no structure of their own). One wind per day is the least-
// squares velocity over the frame pairs, weighted by each pair's correlation peak.
//
// Conventions: those of clouds::CloudParams (wind_direction_deg: the azimuth the wind blows
// toward, 0 -> +z, 90 -> +x; the march samples the map at x + wind offset, offset =
// -direction x speed x time) and of the weather map (column -> +x, row -> +z).
#pragma once
#include <vector>

#include "skycal/clouds/cloud_textures.h"

namespace skycal::cloudfit {

struct TimedWeatherMap {
  const clouds::WeatherMap* map = nullptr;
  // Per texel (row-major): > 0.5 where the photo constrained it (weather_constrained.exr);
  // null: every texel.
  const std::vector<float>* constrained = nullptr;
  double time_s = 0.0;  // the frame's time (any origin shared by the day's frames)
};

// How far the clouds moved between two maps: metres along x and z (the second map is the
// first moved by (dx, dz)), the correlation's peak (0..1: how alike the moved maps are).
struct MapShift {
  double dx_m = 0.0, dz_m = 0.0, response = 0.0, dt_s = 0.0;
};

// Throws skycal::Error when the maps are absent, differ in size or extent, or a constraint
// mask is not the map's size.
MapShift MeasureMapShift(const TimedWeatherMap& from, const TimedWeatherMap& to);

struct DayWind {
  double speed_m_s = 0.0;
  double direction_deg = 0.0;   // CloudParams::wind_direction_deg's convention, [0, 360)
  std::vector<MapShift> pairs;  // consecutive frames in time order
};

// The day's wind from >= 2 maps (any order; sorted by time). Throws skycal::Error for fewer
// than two maps or two frames at the same time.
DayWind FitDayWind(std::vector<TimedWeatherMap> maps);

}  // namespace skycal::cloudfit
