#include "charts.h"

#include <plstream.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>

#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/report/plot_devices.h"

namespace skycal::report {
namespace {

constexpr int kPalette = 6;  // colour map 0 slots 2.. for the series
constexpr unsigned char kColours[kPalette][3] = {{31, 90, 180}, {210, 90, 20}, {40, 150, 60},
                                                 {170, 40, 160}, {200, 30, 30}, {90, 90, 90}};

// PLplot reads '#' as the start of an escape sequence: "##" is a literal one.
std::string PlText(const std::string& s) {
  std::string out;
  for (char ch : s) {
    out += ch;
    if (ch == '#') out += '#';
  }
  return out;
}

bool Usable(const Chart& c, double x, double y) { return std::isfinite(x) && std::isfinite(y) && (!c.log_y || y > 0.0); }

// A scratch file for PLplot's output in the system's temporary directory (removed after);
// /tmp where $TMPDIR names no directory (std::filesystem throws there, and a chart must not
// take the report down).
std::string ScratchPath() {
  static std::atomic<int> counter{0};
  std::error_code ec;
  std::filesystem::path dir = std::filesystem::temp_directory_path(ec);
  if (ec || !std::filesystem::is_directory(dir, ec)) dir = "/tmp";
  return (dir /
          (".skycal-chart-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".svg"))
      .string();
}

// The plotted window in axis units (log10 y on a log axis): the points' range, padded.
struct Window {
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
};

// A log axis only where the values span more than a decade (PLplot labels decades).
bool UseLogY(const Chart& c) {
  double lo = INFINITY, hi = -INFINITY;
  for (const ChartSeries& s : c.series) {
    for (double y : s.y) {
      if (std::isfinite(y) && y > 0.0) lo = std::min(lo, y), hi = std::max(hi, y);
    }
  }
  return std::isfinite(lo) && hi / lo > 10.0;
}

Window ChartWindow(const Chart& c) {
  Window wnd;
  double &x0 = wnd.x0, &x1 = wnd.x1, &y0 = wnd.y0, &y1 = wnd.y1;
  for (const ChartSeries& s : c.series) {
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!Usable(c, s.x[i], s.y[i])) continue;
      const double y = c.log_y ? std::log10(s.y[i]) : s.y[i];
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
  }
  if (!std::isfinite(x0)) throw Error("chart '" + c.title + "': no finite point to draw");
  if (std::isfinite(c.x_min) && std::isfinite(c.x_max)) x0 = std::min(x0, c.x_min), x1 = std::max(x1, c.x_max);
  if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
  if (y1 - y0 < 1e-12 * std::max(1.0, std::abs(y0))) {
    const double pad = c.log_y ? 0.5 : std::max(std::abs(y0) * 0.1, 1e-9);
    y0 -= pad;
    y1 += pad;
  }
  return wnd;
}

// One series' dots (and line, broken at unusable points) in its palette colour, and its
// key line at line_at; returns the next key line's position.
double DrawSeries(plstream& pls, const Chart& c, size_t k, double line_at) {
  const ChartSeries& s = c.series[k];
  pls.col0(2 + static_cast<int>(k % kPalette));
  pls.width(2.0);
  std::vector<PLFLT> xs, ys;
  auto flush = [&]() {
    if (s.line && xs.size() > 1) pls.line(static_cast<PLINT>(xs.size()), xs.data(), ys.data());
    xs.clear();
    ys.clear();
  };
  pls.ssym(0.0, 1.1);
  for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
    if (!Usable(c, s.x[i], s.y[i])) {
      flush();
      continue;
    }
    const PLFLT x = s.x[i], y = c.log_y ? std::log10(s.y[i]) : s.y[i];
    xs.push_back(x);
    ys.push_back(y);
    pls.poin(1, &x, &y, 17);
  }
  flush();
  pls.schr(0.0, 0.72);
  pls.mtex("b", line_at, 0.0, 0.0, PlText((s.line ? "line and dots: " : "dots: ") + s.label).c_str());
  return line_at + 1.9;
}

void Draw(const Chart& chart, const std::string& path) {
  Chart c = chart;
  if (c.log_y) c.log_y = UseLogY(c);
  const Window wnd = ChartWindow(c);
  const double x0 = wnd.x0, x1 = wnd.x1, y0 = wnd.y0, y1 = wnd.y1;
  const double mx = 0.04 * (x1 - x0), my = 0.08 * (y1 - y0);

  plstream pls;
  pls.sdev("svgcairo");
  pls.sfnam(path.c_str());
  pls.setopt("geometry", "900x520");
  pls.scol0(0, 255, 255, 255);
  pls.scol0(1, 0, 0, 0);
  for (int k = 0; k < kPalette; ++k) pls.scol0(2 + k, kColours[k][0], kColours[k][1], kColours[k][2]);
  pls.scol0(8, 200, 200, 200);
  pls.init();
  pls.sxax(8, 0);
  pls.syax(8, 0);
  pls.adv(0);
  const size_t key_lines = c.series.size() + c.notes.size();
  const double bottom = std::min(0.55, 0.17 + 0.05 * static_cast<double>(key_lines));
  pls.vpor(0.14, 0.97, bottom, 0.90);
  pls.wind(x0 - mx, x1 + mx, y0 - my, y1 + my);
  pls.col0(8);
  pls.box("g", 0.0, 0, (std::string("g") + (c.log_y ? "l" : "")).c_str(), 0.0, 0);
  pls.col0(1);
  pls.box("bcnst", 0.0, 0, (std::string("bcnstv") + (c.log_y ? "l" : "")).c_str(), 0.0, 0);
  pls.schr(0.0, 0.95);
  pls.mtex("t", 1.5, 0.5, 0.5, PlText(c.title).c_str());
  pls.schr(0.0, 0.85);
  pls.mtex("b", 3.6, 0.5, 0.5, PlText(c.x_label).c_str());
  pls.mtex("l", 7.0, 0.5, 0.5, PlText(c.y_label + (c.log_y ? ", log scale" : "")).c_str());
  double line_at = 5.8;
  for (size_t k = 0; k < c.series.size(); ++k) line_at = DrawSeries(pls, c, k, line_at);
  pls.col0(1);
  pls.schr(0.0, 0.72);
  for (const std::string& n : c.notes) {
    pls.mtex("b", line_at, 0.0, 0.0, PlText(n).c_str());
    line_at += 1.9;
  }
}

}  // namespace

std::string ChartSvg(const Chart& chart) {
  std::string why;
  if (!PlotDeviceAvailable("svgcairo", &why)) throw Error("chart '" + chart.title + "': " + why);  // PLplot would exit()
  const std::string path = ScratchPath();
  TemporaryGuard guard(path);
  struct Remove {
    std::string p;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove(p, ec);
    }
  } remove{path};
  Draw(chart, path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) || std::filesystem::file_size(path, ec) == 0) {
    throw Error("chart '" + chart.title + "': PLplot wrote no SVG (is Debian's plplot-driver-cairo installed?)");
  }
  return ReadFile(path);
}

}  // namespace skycal::report
