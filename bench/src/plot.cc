#include "skycal/bench/plot.h"

#include <plstream.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>

#include "skycal/core/error.h"
#include "skycal/report/plot_devices.h"

namespace skycal::bench {
namespace {

// Colour map 0 slots (PLplot's palette indices) used below.
enum Colour { kBackground = 0, kInk = 1, kGrey = 2, kFront = 3, kDefault = 4 };

struct Axis {
  bool log = false;
  double lo = 0.0, hi = 1.0;  // in plotted units (log10 when log)
  double floor = 0.0;         // log axes: values <= 0 are drawn here (data units)
  double Map(double v) const { return log ? std::log10(std::max(v, floor)) : v; }
};

// Log when every value is positive (or a few are 0, drawn at a floor) and they span more than
// a decade; a margin of 10% either side.
Axis ChooseAxis(const std::vector<double>& v) {
  Axis a;
  double min_pos = INFINITY, max_v = -INFINITY, min_v = INFINITY;
  for (double x : v) {
    if (x > 0.0) min_pos = std::min(min_pos, x);
    max_v = std::max(max_v, x);
    min_v = std::min(min_v, x);
  }
  if (v.empty()) return a;
  a.log = std::isfinite(min_pos) && min_v >= 0.0 && max_v / min_pos > 10.0;
  if (a.log) {  // decades
    a.floor = min_pos / 3.0;
    a.lo = std::log10(min_v > 0.0 ? min_pos : a.floor);
    a.hi = std::log10(max_v);
  } else {
    a.lo = min_v;
    a.hi = max_v;
  }
  if (a.hi - a.lo < 1e-12) {
    a.lo -= a.log ? 0.5 : std::max(std::abs(a.lo) * 0.1, 1e-12);
    a.hi += a.log ? 0.5 : std::max(std::abs(a.hi) * 0.1, 1e-12);
  }
  const double margin = 0.10 * (a.hi - a.lo);
  a.lo -= margin;
  a.hi += margin;
  return a;
}

// Characters of the title per line at its size on the 1200-pixel-wide page (measured:
// ~95 fit; a margin for wide glyphs).
constexpr size_t kTitleChars = 88;

// `text` in lines of at most `width` characters, broken at spaces (a longer word stays whole).
std::vector<std::string> WrapAtSpaces(const std::string& text, size_t width) {
  std::vector<std::string> lines;
  std::string rest = text;
  while (rest.size() > width) {
    size_t cut = rest.rfind(' ', width);
    if (cut == std::string::npos || cut == 0) cut = rest.find(' ', width);
    if (cut == std::string::npos) break;
    lines.push_back(rest.substr(0, cut));
    rest = rest.substr(cut + 1);
  }
  lines.push_back(rest);
  return lines;
}

// The cases' times and errors, the axes they choose and which cases are on the front.
struct PlotData {
  std::vector<double> t, e;
  Axis ax, ay;
  std::vector<bool> on_front;
};

// Frame with room below for the key, left for the y label; the title, axis labels and subtitle.
void DrawFrame(plstream& pls, const ParetoPlot& p, const PlotData& d) {
  const Axis &ax = d.ax, &ay = d.ay;
  const std::vector<double>& e = d.e;
  pls.adv(0);
  pls.vpor(0.11, 0.97, 0.22, 0.86);
  pls.wind(ax.lo, ax.hi, ay.lo, ay.hi);
  pls.col0(kInk);
  pls.box((std::string("bcnstg") + (ax.log ? "l" : "")).c_str(), 0.0, 0, (std::string("bcnstvg") + (ay.log ? "l" : "")).c_str(), 0.0, 0);
  const std::string xl = "median wall time per case (ms)" + std::string(ax.log ? ", log scale" : "");
  std::string yl = p.error_label + (ay.log ? ", log scale" : "");
  if (ay.log && std::any_of(e.begin(), e.end(), [](double v) { return v <= 0.0; })) yl += " (0 drawn at the floor)";
  pls.schr(0.0, 0.85);
  // A long title (a suite's summary) wraps at a space onto a second line above the
  // first, rather than running off the page.
  const std::vector<std::string> title = WrapAtSpaces(p.title, kTitleChars);
  for (size_t i = 0; i < title.size(); ++i)
    pls.mtex("t", 3.2 + 1.3 * static_cast<double>(title.size() - 1 - i), 0.5, 0.5, title[i].c_str());
  pls.schr(0.0, 0.8);
  pls.mtex("b", 3.0, 0.5, 0.5, xl.c_str());
  pls.mtex("l", 6.0, 0.5, 0.5, yl.c_str());
  pls.schr(0.0, 0.65);
  pls.mtex("t", 1.8, 0.5, 0.5, p.subtitle.c_str());
}

// Dominated cases as grey crosses; the front as a staircase in time order and filled circles.
void DrawPoints(plstream& pls, const ParetoPlot& p, const PlotData& d) {
  const Axis &ax = d.ax, &ay = d.ay;
  const std::vector<double>&t = d.t, &e = d.e;
  // Dominated: grey crosses.
  pls.col0(kGrey);
  pls.ssym(0.0, 1.4);
  for (size_t i = 0; i < p.cases.size(); ++i) {
    if (d.on_front[i]) continue;
    const PLFLT x = ax.Map(t[i]), y = ay.Map(e[i]);
    pls.poin(1, &x, &y, 5);
  }
  // The front: a staircase in time order, then filled circles.
  std::vector<int> order(p.front);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return t[a] < t[b]; });
  pls.col0(kFront);
  pls.width(2.0);
  std::vector<PLFLT> sx, sy;
  for (size_t k = 0; k < order.size(); ++k) {
    if (k > 0) {
      sx.push_back(ax.Map(t[order[k]]));
      sy.push_back(ay.Map(e[order[k - 1]]));
    }
    sx.push_back(ax.Map(t[order[k]]));
    sy.push_back(ay.Map(e[order[k]]));
  }
  if (sx.size() > 1) pls.line(static_cast<PLINT>(sx.size()), sx.data(), sy.data());
  pls.ssym(0.0, 1.6);
  for (int i : order) {
    const PLFLT x = ax.Map(t[i]), y = ay.Map(e[i]);
    pls.poin(1, &x, &y, 17);
  }
}

// Labels beside the points (front in blue first, then grey), small; a label that would
// overlap one already placed tries the other side, above and below, else is left out
// (every case is in results.csv). Boxes in fractions of the frame, character sizes
// measured on the 1200-pixel-wide output at this character scale. Returns the default's
// tag position (fractions of the frame): below its ring (above when the ring is near the
// bottom), kept inside the frame; its box is reserved before the other labels.
std::pair<double, double> DrawLabels(plstream& pls, const ParetoPlot& p, const PlotData& d) {
  const Axis &ax = d.ax, &ay = d.ay;
  const std::vector<double>&t = d.t, &e = d.e;
  const std::vector<bool>& on_front = d.on_front;
  pls.schr(0.0, 0.55);
  struct Box {
    double x0, x1, y0, y1;
  };
  std::vector<Box> placed;
  std::vector<size_t> label_order;
  for (size_t i = 0; i < p.cases.size() && i < p.labels.size(); ++i)
    if (on_front[i]) label_order.push_back(i);
  for (size_t i = 0; i < p.cases.size() && i < p.labels.size(); ++i)
    if (!on_front[i]) label_order.push_back(i);
  double tag_fx = 0.5, tag_fy = 0.5;
  if (p.default_index >= 0) {
    const double fx = (ax.Map(t[p.default_index]) - ax.lo) / (ax.hi - ax.lo);
    const double fy = (ay.Map(e[p.default_index]) - ay.lo) / (ay.hi - ay.lo);
    tag_fx = std::clamp(fx, 0.15, 0.85);
    tag_fy = fy > 0.15 ? fy - 0.08 : fy + 0.08;
    placed.push_back({tag_fx - 0.14, tag_fx + 0.14, tag_fy - 0.025, tag_fy + 0.025});
  }
  for (size_t i : label_order) {
    if (p.labels[i].empty()) continue;
    const double fx = (ax.Map(t[i]) - ax.lo) / (ax.hi - ax.lo), fy = (ay.Map(e[i]) - ay.lo) / (ay.hi - ay.lo);
    const double w = 0.0085 * p.labels[i].size(), h = 0.035;
    const double tries[4][3] = {{0.012, 0.0, 0.0}, {-0.012, 0.0, 1.0}, {0.012, 0.045, 0.0}, {0.012, -0.045, 0.0}};
    for (const auto& tr : tries) {
      const double x0 = tr[2] == 0.0 ? fx + tr[0] : fx + tr[0] - w;
      const Box b{x0, x0 + w, fy + tr[1] - h / 2, fy + tr[1] + h / 2};
      bool clash = b.x1 > 1.0 || b.x0 < 0.0;
      for (const Box& o : placed) clash = clash || (b.x0 < o.x1 && o.x0 < b.x1 && b.y0 < o.y1 && o.y0 < b.y1);
      if (clash) continue;
      placed.push_back(b);
      pls.col0(on_front[i] ? kFront : kGrey);
      pls.ptex(ax.lo + (fx + tr[0]) * (ax.hi - ax.lo), ay.lo + (fy + tr[1]) * (ay.hi - ay.lo), 1.0, 0.0, tr[2],
               p.labels[i].c_str());
      break;
    }
  }
  return {tag_fx, tag_fy};
}

void Draw(const ParetoPlot& p, const std::string& device, const std::string& path) {
  plstream pls;
  pls.sdev(device.c_str());
  pls.sfnam(path.c_str());
  pls.setopt("geometry", "1200x860");
  pls.scol0(kBackground, 255, 255, 255);
  pls.scol0(kInk, 0, 0, 0);
  pls.scol0(kGrey, 170, 170, 170);
  pls.scol0(kFront, 31, 90, 180);
  pls.scol0(kDefault, 210, 30, 30);
  pls.init();
  // Plain numbers on the axes, never a separate "(x10^-3)" that collides with the title.
  pls.sxax(12, 0);
  pls.syax(12, 0);
  pls.schr(0.0, 0.9);

  PlotData pd;
  for (const CaseResult* c : p.cases) {
    pd.t.push_back(c->time.median_ms);
    pd.e.push_back(c->error);
  }
  pd.ax = ChooseAxis(pd.t), pd.ay = ChooseAxis(pd.e);
  const Axis &ax = pd.ax, &ay = pd.ay;
  DrawFrame(pls, p, pd);
  pd.on_front.assign(p.cases.size(), false);
  for (int i : p.front) pd.on_front[i] = true;
  DrawPoints(pls, p, pd);
  const auto [tag_fx, tag_fy] = DrawLabels(pls, p, pd);
  // The default: a red ring and its name.
  if (p.default_index >= 0 && p.default_index < static_cast<int>(p.cases.size())) {
    const int d = p.default_index;
    const PLFLT x = ax.Map(pd.t[d]), y = ay.Map(pd.e[d]);
    pls.col0(kDefault);
    pls.ssym(0.0, 3.5);
    pls.width(2.5);
    pls.poin(1, &x, &y, 4);
    pls.schr(0.0, 0.8);
    const std::string tag = pd.on_front[d] ? "default (on the front)" : "default (dominated)";
    pls.ptex(ax.lo + tag_fx * (ax.hi - ax.lo), ay.lo + tag_fy * (ay.hi - ay.lo), 1.0, 0.0, 0.5, tag.c_str());
  }
  // Key, below the x label.
  pls.schr(0.0, 0.7);
  pls.col0(kFront);
  pls.mtex("b", 5.0, 0.0, 0.0, "blue dots and line: the Pareto front (no other case is both faster and more accurate)");
  pls.col0(kGrey);
  pls.mtex("b", 6.5, 0.0, 0.0, "grey crosses: dominated settings (labels: the settings that differ from the default)");
  pls.col0(kDefault);
  pls.mtex("b", 8.0, 0.0, 0.0, "red ring: the default setting");
}

}  // namespace

void WriteParetoPlot(const ParetoPlot& p, const std::string& png_path, const std::string& svg_path) {
  for (const auto& [device, path] : {std::pair{std::string("pngcairo"), png_path}, std::pair{std::string("svgcairo"), svg_path}}) {
    std::string why;
    if (!report::PlotDeviceAvailable(device, &why)) throw Error(path + ": " + why);  // PLplot would exit()
    Draw(p, device, path);
    std::error_code ec;
    if (!std::filesystem::exists(path, ec) || std::filesystem::file_size(path, ec) == 0)
      throw Error(path + ": PLplot wrote no " + device + " plot (is Debian's plplot-driver-cairo installed?)");
  }
}

}  // namespace skycal::bench
