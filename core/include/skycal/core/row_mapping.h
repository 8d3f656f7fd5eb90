// Horizon-biased rows of a lat-long frame (Forza Horizon 3's game frames: "almost double
// the vertical resolution" at the horizon, the top of the sky at a quarter; GDC talk "The
// Ambitious HDR Time-lapse Skies of Forza Horizon 3"). Columns keep core/latlong.h's
// longitudes; rows follow a smooth, strictly monotone map from the node-centred row
// coordinate y in [0, rows - 1] to the elevation e (radians, +pi/2 at y = 0, -pi/2 at
// y = rows - 1), with the horizon (e = 0) at the row coordinate y_h:
//
//   above the horizon (y <= y_h):  s = (y_h - y) / y_h,                e =  pi/2 sinh(b_up s)   / sinh(b_up)
//   below the horizon (y >= y_h):  s = (y - y_h) / (rows - 1 - y_h),   e = -pi/2 sinh(b_down s) / sinh(b_down)
//
// (b = 0: the linear limit e = +-pi/2 s). The row density dy/de falls as 1 / cosh(b s) away
// from the horizon, so cosh(b_up) is the density ratio horizon : zenith (8 for FH3's 2x and
// 1/4). y_h = (rows - 1) c_up / (c_up + c_down) with c = b / sinh(b) makes de/dy continuous
// at the horizon. The inverse is closed form (asinh), exact to rounding. A file stores the
// three defining numbers in the string attribute `skycalRowMapping` as JSON:
//   {"mapping": "horizon-sinh", "version": 1, "rows": 297, "b_up": 2.7687, "b_down": 2.7687}
#pragma once
#include <array>
#include <optional>
#include <string>

#include "skycal/core/image.h"

namespace skycal {

inline constexpr const char* kRowMappingAttribute = "skycalRowMapping";

struct RowMapping {
  int rows = 0;         // the frame's height (pixels)
  double b_up = 0.0;    // shape above the horizon, >= 0 (0: uniform rows)
  double b_down = 0.0;  // shape below the horizon, >= 0

  bool IsValid(std::string* why) const;

  double HorizonRow() const;            // y_h (continuous row coordinate)
  double Elevation(double y) const;     // radians; y in [0, rows - 1] (clamped)
  double Row(double elevation) const;   // the exact inverse; elevation in [-pi/2, pi/2] (clamped)
  double Density(double elevation) const;  // dy/de, rows per radian
  // Solid angle (sr) of pixel (x, y) of a `width`-wide frame: the elevation band between the
  // half-rows either side (clipped at the poles) times core/latlong.h's column width (the
  // two seam columns share one). Sums to 4 pi over the frame.
  double PixelSolidAngle(int x, int y, int width) const;
  std::array<double, 3> PixelDirection(int x, int y, int width) const;

  std::string ToAttribute() const;  // the JSON string above
  // Parses the attribute; throws skycal::Error naming `where` (the file), the attribute,
  // the field and what was expected.
  static RowMapping FromAttribute(const std::string& text, const std::string& where);

  // The mapping that gives `horizon_density` times, `zenith_density` times and
  // `nadir_density` times the row density of a uniform lat-long `source_height` rows
  // high at the horizon, the zenith and the nadir (densities > 0, the horizon's the
  // largest); rows rounded to whole pixels (the horizon density then moves by < 1 row).
  static RowMapping ForDensities(int source_height, double horizon_density, double zenith_density,
                                 double nadir_density);
};

// A uniform lat-long (core/latlong.h, any height >= 2) onto the mapping's rows, same
// columns: each output row is the mean, over its elevation band (half a row either side,
// clipped at the poles), of the source's row-wise linear interpolant (exact integral of it
// in source-row coordinates; the cos(elevation) weight inside a band is left out). Where
// the mapping is coarser than the source this averages the rows it covers (no aliasing);
// where finer it interpolates. The horizon is an edge: a row above it reads the source's
// rows above it only (the last two extended linearly to the horizon), likewise below.
// Non-finite source values (invalid pixels) are masked: an output value averages the finite
// source values it covers (the same integral of a 0/1 validity divides the integral of the
// values with the invalid ones zeroed), so one NaN or inf never reaches another row's or
// column's value. An output value that covers no finite source (validity integral below
// one half) is written as 0 and counted in `*unsourced` (when given).
ImageRGB ResampleToRows(const ImageRGB& uniform, const RowMapping& mapping, long long* unsourced = nullptr);

// The height of a uniform lat-long at least as dense as `mapping` everywhere (its
// densest rows are at the horizon), for rendering a model before ResampleToRows.
int UniformHeightCovering(const RowMapping& mapping);

}  // namespace skycal
