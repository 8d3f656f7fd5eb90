#include "skycal/cloudfit/weather_wind.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "skycal/core/error.h"
#include "skycal/core/math_constants.h"

namespace skycal::cloudfit {
namespace {

// The coverage channel as a double image; texels the photo left alone take the mean of the
// constrained ones, so that only what the photo saw correlates.
cv::Mat Coverage(const TimedWeatherMap& m, cv::Mat* seen_out) {
  const clouds::WeatherMap& w = *m.map;
  const size_t n = static_cast<size_t>(w.width) * w.height;
  const auto seen = [&](size_t i) { return !m.constrained || (*m.constrained)[i] > 0.5f; };
  double sum = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < n; ++i)
    if (seen(i)) {
      sum += w.rgb[3 * i];
      ++count;
    }
  const double mean = count ? sum / static_cast<double>(count) : 0.0;
  cv::Mat c(w.height, w.width, CV_64F);
  *seen_out = cv::Mat(w.height, w.width, CV_8U);
  for (size_t i = 0; i < n; ++i) {
    const int y = static_cast<int>(i / w.width), x = static_cast<int>(i % w.width);
    c.at<double>(y, x) = seen(i) ? w.rgb[3 * i] : mean;
    seen_out->at<uchar>(y, x) = seen(i) ? 1 : 0;
  }
  return c;
}

// Bilinear sample of a periodic image at (x, y), texels.
double Periodic(const cv::Mat& m, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  const auto at = [&](int i, int j) { return m.at<double>((j % m.rows + m.rows) % m.rows, (i % m.cols + m.cols) % m.cols); };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// The correlation peak's sub-texel part is a weighted centroid, biased toward whole texels
// (by a fifth of a texel at a shift of 1.3); Gauss-Newton on the squared difference between
// `b` and `a` moved by d (Lucas & Kanade 1981) takes it from there.
// Only texels seen in `b` whose source in `a` is seen with its neighbours (`a_seen`, `b_seen`:
// CV_8U, 1 seen) count: the mean that fills the rest has edges that do not move.
cv::Point2d RefineShift(const cv::Mat& a, const cv::Mat& b, const cv::Mat& a_seen, const cv::Mat& b_seen, cv::Point2d d) {
  cv::Mat inner(a_seen.size(), CV_8U);  // seen with every texel within 2 (cv::erode has no wrapping border)
  for (int y = 0; y < a_seen.rows; ++y)
    for (int x = 0; x < a_seen.cols; ++x) {
      bool all = true;
      for (int j = -2; j <= 2 && all; ++j)
        for (int i = -2; i <= 2 && all; ++i)
          all = a_seen.at<uchar>((y + j + a_seen.rows) % a_seen.rows, (x + i + a_seen.cols) % a_seen.cols) != 0;
      inner.at<uchar>(y, x) = all ? 1 : 0;
    }
  for (int it = 0; it < 8; ++it) {
    double hxx = 0.0, hxy = 0.0, hyy = 0.0, gx = 0.0, gy = 0.0;
    for (int y = 0; y < b.rows; ++y)
      for (int x = 0; x < b.cols; ++x) {
        const double sx = x - d.x, sy = y - d.y;
        const int ix = static_cast<int>(std::lround(sx)), iy = static_cast<int>(std::lround(sy));
        if (!b_seen.at<uchar>(y, x) ||
            !inner.at<uchar>((iy % b.rows + b.rows) % b.rows, (ix % b.cols + b.cols) % b.cols))
          continue;
        const double r = b.at<double>(y, x) - Periodic(a, sx, sy);
        // d(moved a)/d(d) = -grad a at the source.
        const double jx = -(Periodic(a, sx + 0.5, sy) - Periodic(a, sx - 0.5, sy));
        const double jy = -(Periodic(a, sx, sy + 0.5) - Periodic(a, sx, sy - 0.5));
        hxx += jx * jx, hxy += jx * jy, hyy += jy * jy, gx += jx * r, gy += jy * r;
      }
    const double det = hxx * hyy - hxy * hxy;
    if (!(det > 0.0)) break;
    const cv::Point2d step((hyy * gx - hxy * gy) / det, (hxx * gy - hxy * gx) / det);
    if (std::hypot(step.x, step.y) > 1.0) break;  // not in the peak's basin: keep the correlation's
    d += step;
    if (std::hypot(step.x, step.y) < 1e-3) break;
  }
  return d;
}

void CheckMap(const TimedWeatherMap& m, const char* which) {
  if (!m.map || m.map->width <= 0 || m.map->rgb.size() != 3u * m.map->width * m.map->height)
    throw Error(std::string("MeasureMapShift: the ") + which + " map is absent or malformed");
  if (m.constrained && m.constrained->size() != static_cast<size_t>(m.map->width) * m.map->height)
    throw Error(std::string("MeasureMapShift: the ") + which + " map's constraint mask is not the map's size");
}

}  // namespace

MapShift MeasureMapShift(const TimedWeatherMap& from, const TimedWeatherMap& to) {
  CheckMap(from, "first");
  CheckMap(to, "second");
  if (from.map->width != to.map->width || from.map->height != to.map->height || from.map->extent_m != to.map->extent_m)
    throw Error("MeasureMapShift: the maps differ in size or extent (" + std::to_string(from.map->width) + " and " +
                std::to_string(to.map->width) + " texels)");
  double response = 0.0;
  // phaseCorrelate(a, b) is the shift that carries a onto b, in texels (column, row).
  cv::Mat a_seen, b_seen;
  const cv::Mat a = Coverage(from, &a_seen), b = Coverage(to, &b_seen);
  const cv::Point2d s = RefineShift(a, b, a_seen, b_seen, cv::phaseCorrelate(a, b, cv::noArray(), &response));
  MapShift r;
  r.dx_m = s.x * from.map->extent_m / from.map->width;
  r.dz_m = s.y * from.map->extent_m / from.map->height;
  r.response = response;
  r.dt_s = to.time_s - from.time_s;
  return r;
}

DayWind FitDayWind(std::vector<TimedWeatherMap> maps) {
  if (maps.size() < 2) throw Error("FitDayWind: " + std::to_string(maps.size()) + " map(s) (expected at least 2)");
  std::sort(maps.begin(), maps.end(), [](const auto& a, const auto& b) { return a.time_s < b.time_s; });
  DayWind d;
  // Least squares of shift = v dt over the pairs, each weighted by its peak: v = sum w s dt / sum w dt^2.
  double sx = 0.0, sz = 0.0, st = 0.0;
  for (size_t k = 1; k < maps.size(); ++k) {
    if (!(maps[k].time_s > maps[k - 1].time_s))
      throw Error("FitDayWind: two frames at the same time (" + std::to_string(maps[k].time_s) + " s)");
    const MapShift s = MeasureMapShift(maps[k - 1], maps[k]);
    d.pairs.push_back(s);
    sx += s.response * s.dx_m * s.dt_s;
    sz += s.response * s.dz_m * s.dt_s;
    st += s.response * s.dt_s * s.dt_s;
  }
  const double vx = st > 0.0 ? sx / st : 0.0, vz = st > 0.0 ? sz / st : 0.0;
  d.speed_m_s = std::hypot(vx, vz);
  d.direction_deg = std::fmod(std::atan2(vx, vz) * kDegreesPerRadian + 360.0, 360.0);
  return d;
}

}  // namespace skycal::cloudfit
