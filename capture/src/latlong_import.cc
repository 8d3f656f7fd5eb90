#include "skycal/capture/latlong_import.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

// Blender's equirectangular mapping (Cycles kernel/geom `direction_to_equirectangular`,
// range (-2pi, pi, -pi, pi); EEVEE `node_tex_environment_equirectangular`), for a world
// direction b (Blender is Z up):
//   u = -atan2(b.y, b.x) / (2 pi) + 0.5        v = atan2(b.z, hypot(b.x, b.y)) / pi + 0.5
// with (u, v) in [0, 1]^2 and v = 0 at the image's bottom. The EXR stores row 0 at the top
// and Blender samples texel (i, j) at its centre: u = (i + 0.5) / W, v = 1 - (j + 0.5) / H.
//
// The project (core/latlong.h): longitude = atan2(d.x, d.z), latitude = asin(d.y), node
// (x, y) at x / (W - 1) = 0.5 - longitude / (2 pi), y / (H - 1) = 0.5 - latitude / pi.
//
// With d = (b.y, b.z, b.x) the longitude is atan2(b.y, b.x), so x / (W - 1) = u and
// y / (H - 1) = 1 - v: the picture maps onto ours without any flip or shift. The map
// (x, y, z)_blender -> (y, z, x)_project is a proper rotation (a cyclic axis permutation,
// det +1: 120 deg about (1, 1, 1) / sqrt 3), so nothing is mirrored: Blender +X (image
// centre) -> project +Z (longitude 0, image centre); Blender +Y (left quarter) -> +X
// (longitude +90 deg); Blender +Z (up) -> +Y. Only the sample positions differ (texel
// centres vs nodes), hence the bilinear resampling: node x sits at source column
// x W / (W - 1) - 0.5 (wrapping), node y at source row y H / (H - 1) - 0.5 (clamped).

namespace skycal::capture {
namespace {

// Continuous source pixel position (column, row) of a project direction.
std::array<double, 2> SourcePosition(const latlong::Vec3d& d, SourceConvention c, int w, int h) {
  if (c == SourceConvention::kExr) return latlong::PixelPosition(d, w, h);
  // Project -> Blender: the inverse of (x, y, z)_b -> (y, z, x)_p is (x, y, z)_p -> (z, x, y)_b.
  const double bx = d[2], by = d[0], bz = d[1];
  const double u = -std::atan2(by, bx) / (2.0 * kPi) + 0.5;
  const double v = std::atan2(bz, std::hypot(bx, by)) / kPi + 0.5;
  return {u * w - 0.5, (1.0 - v) * h - 0.5};
}

// Snaps a coordinate that is an integer up to rounding, so that a same-size exr -> exr
// copy is exact and a NaN neighbour with a zero weight cannot leak in (0 * NaN = NaN).
double Snap(double t) {
  const double r = std::round(t);
  return std::abs(t - r) < 1e-9 ? r : t;
}

}  // namespace

const char* ToString(SourceConvention c) { return c == SourceConvention::kBlender ? "blender" : "exr"; }

SourceConvention ChooseConvention(const ExrAttributes& attributes) {
  return attributes.envmap_latlong ? SourceConvention::kExr : SourceConvention::kBlender;
}

std::array<double, 3> BlenderToProjectDirection(const std::array<double, 3>& b) { return {b[1], b[2], b[0]}; }

ImageRGB ResampleToProjectLatLong(const ImageRGB& src, SourceConvention convention, int out_w, int out_h) {
  ImageRGB out(out_w, out_h);
  const int sw = src.width, sh = src.height;
  // Longitude period in source columns: Blender's texels tile [0, 1) once; the exr
  // convention stores the seam twice (column sw - 1 repeats column 0).
  const int period = convention == SourceConvention::kBlender ? sw : sw - 1;
  auto wrap = [period](long long i) { return static_cast<int>(((i % period) + period) % period); };
  for (int y = 0; y < out_h; ++y) {
    for (int x = 0; x < out_w; ++x) {
      const auto d = latlong::PixelDirection(x, y, out_w, out_h);
      const auto p = SourcePosition(d, convention, sw, sh);
      const double sx = Snap(p[0]), sy = std::clamp(Snap(p[1]), 0.0, static_cast<double>(sh - 1));
      const double fx = std::floor(sx), fy = std::floor(sy);
      const double tx = sx - fx, ty = sy - fy;
      const int x0 = wrap(static_cast<long long>(fx)), x1 = wrap(static_cast<long long>(fx) + 1);
      const int y0 = static_cast<int>(fy), y1 = std::min(y0 + 1, sh - 1);
      const double wts[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
      const int xs[4] = {x0, x1, x0, x1}, ys[4] = {y0, y0, y1, y1};
      for (int c = 0; c < 3; ++c) {
        double acc = 0.0;
        for (int k = 0; k < 4; ++k) {
          if (wts[k] != 0.0) acc += wts[k] * src.at(xs[k], ys[k], c);
        }
        out.at(x, y, c) = static_cast<float>(acc);
      }
    }
  }
  // A pole row is a single direction: give it one radiance, the mean of its finite samples.
  for (int y : {0, out_h - 1}) {
    for (int c = 0; c < 3; ++c) {
      double sum = 0.0;
      int n = 0;
      for (int x = 0; x < out_w; ++x) {
        const float v = out.at(x, y, c);
        if (std::isfinite(v)) {
          sum += v;
          ++n;
        }
      }
      const float mean = n ? static_cast<float>(sum / n) : std::numeric_limits<float>::quiet_NaN();
      for (int x = 0; x < out_w; ++x) out.at(x, y, c) = mean;
    }
  }
  return out;
}

}  // namespace skycal::capture
