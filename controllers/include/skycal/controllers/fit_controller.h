// The fit controller, the pipeline `skycal fit` runs: reference EXRs (+ a user mask, probe
// samples) -> the sky fit -> the clouds (known shapes, fit_clouds.h, or statistics of a
// photograph's cloud pixels, fit_cloud_stats.h) -> preset.json (+ its LUT EXRs and weather
// map), fit/<ref>.exr and previews, report.png, fit.json and report.html. Progress goes to
// stderr ([fit]); errors name the options' fields and values, never a command line's flags.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/controllers/fit_cloud_stats.h"
#include "skycal/controllers/fit_clouds.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/staged_directory.h"
#include "skycal/fit/fit_options.h"

namespace skycal::controllers {

struct FitControllerOptions {
  std::vector<std::string> references;  // lat-long EXRs, >= 1 (several: a day of references)
  std::string init_preset;              // the starting preset; empty: the bundled default_clear preset
  // The output directory: RunFitController creates it atomically (it must hold nothing but an
  // earlier fit's output); RunFitInto writes into the caller's. Either way its name is the
  // fitted preset's name and fit.json's `out`.
  std::string out_dir;
  fit::FitOptions fit;
  bool cloud_mask = false;  // leave pixels of cloud probability >= 0.5 out (fit_cloud_mask.h)
  bool report = true;       // write report.html (skycal_report) over the output directory
  // Write report.png, fit/<ref>.{reference,fit,error}.png and the cloud statistics' panels
  // (fit/<ref>.clouds.*.png). Off for a fit whose outputs the caller replaces: calibrate's
  // statistics fit, when the refit on the placed clouds follows and writes its own.
  bool previews = true;
  // Where the fit's progress lines go, one line each without a prefix (a controller that runs
  // the fit as one of its steps: calibrate); empty: stderr as "[fit] LINE", as `skycal fit`.
  std::function<void(const std::string&)> log;
  // How the records (fit.json, the preset's provenance, fit/<ref>.exr) name a file the fit
  // read: a controller that stages the fit's inputs beside its outputs maps the staging
  // paths to where the files will be once it commits (calibrate); empty: as given.
  std::function<std::string(const std::string&)> record_path;
  // Probe samples (skycal probe-extract) per reference, "REF_STEM=SAMPLES.json"; a reference
  // named in none takes <reference without .exr>.probe.json when that file exists.
  std::vector<std::string> probes;
  bool require_probe = false;       // every reference must have probe samples that see the sun
  FitCloudOptions clouds;           // the known-shapes cloud lighting fit
  FitCloudStatsOptions cloud_stats;  // unknown shapes: statistics of the cloud pixels
  // False and the field (FitControllerOptions::, FitOptions::, FitCloudOptions::,
  // CloudLightingOptions::, PhotoCloudStatsOptions::), its value and the expectation in *why.
  bool IsValid(std::string* why) const;
};

// Every file the fit reads, each named by its field: a caller staging its own directory
// passes them to StagedDirectory, which refuses an output that would replace one.
std::vector<NamedPath> FitControllerInputs(const FitControllerOptions& o);

// Stages out_dir, runs the fit into it (RunFitInto) and commits it. Returns fit.json's
// contents. Throws skycal::Error (nothing is left behind) on invalid options or a failed stage.
nlohmann::json RunFitController(const FitControllerOptions& o);

// Runs the fit into a directory the caller staged (and commits, with its own files beside):
// preset.json (+ LUTs, <stem>.weather.exr, <stem>.cloud_keyframes.json), fit/, report.png,
// fit.json and, with `report`, report.html over everything staged so far. Returns fit.json's
// contents.
nlohmann::json RunFitInto(const FitControllerOptions& o, const StagedDirectory& out);

// The options a fit ran with, as fit.json and the preset's provenance record them.
nlohmann::json ResolvedFitOptionsJson(const fit::FitOptions& fo);

}  // namespace skycal::controllers
