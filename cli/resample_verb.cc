#include "resample_verb.h"

#include <cmath>

#include "command_line.h"
#include "finite_output.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/format_number.h"
#include "skycal/core/row_mapping.h"
#include "verb_common.h"

namespace skycal::cli {

bool ResampleOptions::IsValid(std::string* why) const {
  if (in.empty() || out.empty()) {
    *why = "--in FRAME.exr and --out OUT.exr are required";
    return false;
  }
  for (auto [name, v] : {std::pair{"--horizon-density", horizon_density}, {"--zenith-density", zenith_density},
                         {"--nadir-density", nadir_density}}) {
    if (!(v > 0.0 && v <= 16.0)) {
      *why = std::string(name) + ": expected a factor in (0, 16], found " + FormatNumber(v);
      return false;
    }
  }
  if (nominal_height != 0 && (nominal_height < 3 || nominal_height > kMaxExrSide)) {
    *why = "--nominal-height: expected rows in [3, " + std::to_string(kMaxExrSide) + "]";
    return false;
  }
  if (zenith_density > horizon_density || nadir_density > horizon_density) {
    *why = "--zenith-density and --nadir-density: expected at most --horizon-density (" +
           FormatNumber(horizon_density) + "): the rows are densest at the horizon";
    return false;
  }
  return true;
}

nlohmann::json RunResampleImpl(const ResampleOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  RefuseOutputsOverInputs({{"--out", o.out}}, {{"--in", o.in}});
  capture::LatLongFrame frame = capture::ReadLatLongFrame(o.in);  // uniform rows only: refuses a resampled frame
  const int w = frame.radiance.width, h = frame.radiance.height;
  const int nominal = o.nominal_height > 0 ? o.nominal_height : h;
  const RowMapping m = RowMapping::ForDensities(nominal, o.horizon_density, o.zenith_density, o.nadir_density);
  Log("resample", o.in + ": " + std::to_string(w) + "x" + std::to_string(h) + " -> " + std::to_string(w) + "x" +
                      std::to_string(m.rows) + " (horizon row " + FormatNumber(m.HorizonRow()) + ", b_up " +
                      FormatNumber(m.b_up) + ", b_down " + FormatNumber(m.b_down) + ")");
  long long unsourced = 0;
  frame.radiance = ResampleToRows(frame.radiance, m, &unsourced);
  if (unsourced > 0) {
    Log("resample", o.out + ": " + std::to_string(unsourced) +
                        " values cover only invalid (non-finite) source pixels: written as 0, which the fit masks");
  }
  frame.row_mapping = m;
  PrepareImageForWrite("resample", o.out, &frame.radiance, o.half);
  capture::WriteLatLongFrame(o.out, frame, o.half);
  // Rows per degree as the file has them (the rounding of rows moves them slightly).
  const double uniform = (nominal - 1) / 180.0;
  auto density = [&](double e_deg) { return m.Density(e_deg * M_PI / 180.0) * M_PI / 180.0; };
  nlohmann::json rows_per_degree = nlohmann::json::object();
  for (int e : {90, 45, 10, 0, -45, -90}) rows_per_degree[std::to_string(e)] = density(e);
  Log("resample", "wrote " + o.out + ": " + FormatNumber(density(0) / uniform) + "x the nominal frame's rows per degree at the "
                      "horizon, " + FormatNumber(density(90) / uniform) + "x at the zenith; " +
                      FormatNumber(100.0 * m.rows / h) + "% of its rows");
  return {{"in", o.in},
          {"out", o.out},
          {"width", w},
          {"input_rows", h},
          {"nominal_rows", nominal},
          {"rows", m.rows},
          {"row_fraction", static_cast<double>(m.rows) / h},
          {"horizon_row", m.HorizonRow()},
          {"mapping", nlohmann::json::parse(m.ToAttribute())},
          {"nominal_rows_per_degree", uniform},
          {"rows_per_degree_at_elevation_deg", rows_per_degree}};
}

ResampleOptions ParseResampleArgs(int argc, char** argv) {
  VerbCommandLine cl("resample",
                     "skycal resample: a lat-long frame to horizon-biased rows for the game (more rows per degree\n"
                     "near the horizon, fewer toward the zenith and nadir; same columns)",
                     "  skycal resample --in FRAME.exr --out GAME_FRAME.exr [--nominal-height N] [--horizon-density 2]\n"
                     "                  [--zenith-density 0.25] [--nadir-density 0.25] [--half] [--json]",
                     "Row y maps to elevation e = pi/2 sinh(b s) / sinh(b) (s: the row's distance from the\n"
                     "horizon row as a fraction of the rows above or below it), written to the EXR's\n"
                     "'skycalRowMapping' attribute; `skycal fit` reads the frame through its exact inverse.\n"
                     "Each output row is the mean of the input over its elevation band.");
  ResampleOptions o;
  cl.Text("--in", &o.in, "FRAME.exr", "a uniform 2:1 lat-long frame (capture, import or render)");
  cl.Text("--out", &o.out, "OUT.exr", "the resampled frame (written atomically)");
  cl.Integer("--nominal-height", &o.nominal_height, 3, kMaxExrSide, "expected rows in [3, 32768]", "N",
             "the densities are relative to a uniform lat-long N rows high\n"
             "(default: the input's height; e.g. 512 from an 8K source for a 1K-class game frame)");
  cl.Number("--horizon-density", &o.horizon_density, "X", "rows per degree at the horizon, x the nominal frame's (default 2)");
  cl.Number("--zenith-density", &o.zenith_density, "X", "rows per degree at the zenith, x the nominal frame's (default 0.25)");
  cl.Number("--nadir-density", &o.nadir_density, "X", "rows per degree at the nadir, x the nominal frame's (default 0.25)");
  cl.Flag("--half", &o.half, "write 16-bit floats");
  bool json = false;
  cl.Flag("--json", &json, "print a JSON summary on stdout (rows, mapping, rows per degree)");
  cl.Parse(argc, argv);
  return o;
}

int RunResample(int argc, char** argv) {
  return RunVerb("resample", WantsJson(argc, argv), [&]() { return RunResampleImpl(ParseResampleArgs(argc, argv)); });
}

}  // namespace skycal::cli
