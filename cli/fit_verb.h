// `skycal fit`: fit the sky model to reference skies; writes a calibrated preset, the fit
// renders, report.png and fit.json into an output directory, atomically. The verb parses its
// command line into controllers::FitControllerOptions, runs the fit controller
// (skycal/controllers/fit_controller.h) and prints; the controller's messages name its
// fields, the verb writes them as the flags that set them.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/controllers/fit_controller.h"
#include "skycal/fit/fit_options.h"

namespace skycal::cli {

// FitControllerOptions' fields that `skycal batch` sets too (for each frame's fit).
struct FitVerbOptions {
  std::vector<std::string> references;  // lat-long EXRs
  std::string init_preset;              // empty: the bundled default preset
  std::string out_dir;                  // created atomically (must not hold other files)
  fit::FitOptions fit;
  bool cloud_mask = false;              // leave pixels of cloud probability >= 0.5 out
  bool report = true;                   // write DIR/report.html (skycal report)
  // FitControllerOptions::IsValid, each field written as its flag.
  bool IsValid(std::string* why) const;
};

// The probe options of the command line (not in FitVerbOptions: RunFitImpl(o) uses the
// defaults, auto-discovery of <reference stem>.probe.json, not required).
struct FitProbeOptions {
  std::vector<std::string> probes;  // --probe REF_STEM=SAMPLES.json
  bool require_probe = false;       // every reference must have probe samples
};

using controllers::FitCloudOptions;  // --clouds, --cloud-preset, --cloud-time ...

// --clouds stats and the --cloud-stats-* flags: the controller's options, checked with the
// flags named (the controller's IsValid names the fields).
struct FitCloudStatsOptions : controllers::FitCloudStatsOptions {
  bool IsValid(std::string* why) const;
};

// Everything `skycal fit` takes on its command line.
struct FitCommandLine {
  FitVerbOptions options;
  FitProbeOptions probes;
  FitCloudOptions clouds;
  FitCloudStatsOptions cloud_stats;
  controllers::FitControllerOptions Controller() const;
};

// The fit controller's messages with its options' fields written as the flags that set them.
std::string WithFitControllerFlags(const std::string& message);
// The cloud statistics' messages (PhotoCloudStatsOptions' fields) written with the flags.
std::string WithCloudStatsFlags(const std::string& message);

// The controller's cloud statistics stage, its errors naming the flags; with the two below,
// the names tests/fit_cloud_stats_test.cc calls the stage by.
nlohmann::json RunCloudStatsOnPhotos(const FitCloudStatsOptions& o, const std::vector<cloudfit::CloudStatsPhoto>& photos,
                                     const fit::FitResult& sky, const std::filesystem::path& fit_dir,
                                     cloudfit::CloudStatsPresetUpdate* update = nullptr);
using controllers::AttachCloudStats;
using controllers::RefineCloudMaskAndRefitSky;

// Runs the fit controller on the command line's options (a FitVerbOptions alone: the
// defaults of the rest), with every message naming flags.
nlohmann::json RunFitImpl(const FitCommandLine& c);
nlohmann::json RunFitImpl(const FitVerbOptions& options);

// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
FitCommandLine ParseFitArgs(int argc, char** argv);
int RunFit(int argc, char** argv);

}  // namespace skycal::cli
