// `skycal fit`: fit the sky model to reference skies; writes a calibrated preset, the fit
// renders, report.png and fit.json into an output directory, atomically.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit_cloud_stats.h"
#include "fit_clouds.h"
#include "skycal/fit/fit_options.h"

namespace skycal::cli {

struct FitVerbOptions {
  std::vector<std::string> references;  // lat-long EXRs
  std::string init_preset;              // empty: the bundled default preset
  std::string out_dir;                  // created atomically (must not hold other files)
  fit::FitOptions fit;
  bool cloud_mask = false;              // leave pixels of cloud probability >= 0.5 out (fit_cloud_mask.h)
  bool report = true;                   // write DIR/report.html (skycal report)
  bool IsValid(std::string* why) const;
};

// The probe options of the command line (not in FitVerbOptions: RunFitImpl(o) uses the
// defaults, auto-discovery of <reference stem>.probe.json, not required).
struct FitProbeOptions {
  std::vector<std::string> probes;  // --probe REF_STEM=SAMPLES.json
  bool require_probe = false;       // every reference must have probe samples
};

// Everything `skycal fit` takes on its command line.
struct FitCommandLine {
  FitVerbOptions options;
  FitProbeOptions probes;
  FitCloudOptions clouds;  // --clouds, --cloud-preset, --cloud-time ... (fit_clouds.h)
  FitCloudStatsOptions cloud_stats;  // --clouds stats, --cloud-stats-* (fit_cloud_stats.h)
};

nlohmann::json RunFitImpl(const FitVerbOptions& options);

// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
FitCommandLine ParseFitArgs(int argc, char** argv);
int RunFit(int argc, char** argv);

}  // namespace skycal::cli
