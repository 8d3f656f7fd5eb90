// Whether PLplot can draw on a device, asked before any plot is started. PLplot ends the
// process (plexit calls exit()) when it cannot open a device: a machine without Debian's
// plplot-driver-cairo, or PLPLOT_DRV_DIR naming an empty or absent directory. Even its
// device list (plgDevs) exits on an empty driver directory and crashes on an absent one,
// so the check reads the driver directory the way PLplot's plInitDispatchTable does,
// without calling PLplot: DIR/*.driver_info lines "device:description:interactive:
// module:sequence:tag", and DIR/<module>.so must load. Plots are optional everywhere in
// skycal: a caller that gets false leaves the plot out, says why, and keeps its results.
#pragma once
#include <string>

namespace skycal::report {

// True when `device` (e.g. "svgcairo", "pngcairo") is listed and its module loads; else
// false with `why` naming the driver directory, what is missing and the package to install.
// The answer is computed once per device and process. Also installs PLplot's abort and exit
// handlers (InstallPlplotHandlers).
bool PlotDeviceAvailable(const std::string& device, std::string* why);

// PLplot's abort handler (plsabort) keeps its messages out of the verb's log (the
// availability check reports the cause), and its exit handler
// (plsexit) names skycal's remedy before PLplot exits. Idempotent.
void InstallPlplotHandlers();

}  // namespace skycal::report
