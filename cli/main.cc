// skycal: one binary, verbs (COLMAP style). Each verb parses its options into a struct
// and calls a testable Run<Verb>Impl.
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "bake_verb.h"
#include "batch_verb.h"
#include "bench_verb.h"
#include "capture_verb.h"
#include "chart_verb.h"
#include "calibrate_verb.h"
#include "compare_verb.h"
#include "ceiling_verb.h"
#include "export_verb.h"
#include "fit_verb.h"
#include "import_verb.h"
#include "mask_verb.h"
#include "stars_verb.h"
#include "probe_extract_verb.h"
#include "probe_predict_verb.h"
#include "render_verb.h"
#include "report_verb.h"
#include "sun_verb.h"
#include "flow_verb.h"
#include "resample_verb.h"
#include "weather_verb.h"
#include "skycal/core/huge_pages.h"
#include "skycal/core/interrupt_cleanup.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/version.h"

namespace {

struct Verb {
  const char* name;
  const char* summary;
  int (*run)(int argc, char** argv);
};

const std::vector<Verb>& Verbs() {
  static const std::vector<Verb> verbs = {
      {"calibrate", "photographs in, calibrated presets out: sky found, sun placed, kind of sky decided, fitted, the game's image beside the photo", &skycal::cli::RunCalibrate},
      {"render", "render a sky preset to a lat-long EXR (+ PNG preview)", &skycal::cli::RunRender},
      {"bake", "bake a preset's LUTs from a single-scattering Earth atmosphere", &skycal::cli::RunBake},
      {"ceiling", "the model's best possible fit of a reference sky (rel RMSE), LUT and per image row", &skycal::cli::RunCeiling},
      {"capture", "exposure brackets (fisheye or rig) to a calibrated lat-long reference frame", &skycal::cli::RunCapture},
      {"chart", "a colour-chart correction (ColorChecker -> 3x3 to scene-linear Rec.709) for capture", &skycal::cli::RunChart},
      {"compare", "the game's image of a sky against the photo: per-pixel log RMSE, appearance error, and where the clouds sit", &skycal::cli::RunCompare},
      {"export", "write game tables (half-float LUTs, time-of-day keyframes) from presets", &skycal::cli::RunExport},
      {"fit", "fit the sky model to HDR reference skies (Ceres), write a calibrated preset", &skycal::cli::RunFit},
      {"batch", "calibrate a time-lapse day frame by frame (local cores or Slurm), then the day's fit and tables", &skycal::cli::RunBatch},
      {"import", "convert a published HDR panorama (Blender/Poly Haven) to a reference frame", &skycal::cli::RunImport},
      {"flow", "motion vectors between two time-lapse frames (quarter res, 8-bit + per-frame range sidecar)", &skycal::cli::RunFlow},
      {"resample", "a lat-long frame to horizon-biased rows for the game (fit reads them through the exact inverse)", &skycal::cli::RunResample},
      {"mask", "find what is not sky in a reference frame (buildings, trees, terrain): a mask for fit --mask", &skycal::cli::RunMask},
      {"stars", "remove the stars of a night frame (small isolated point sources -> local median), count and mask them", &skycal::cli::RunStars},
      {"probe-extract", "measure the gray diffuse ball in a linear EXR: samples by normal for fit --probe", &skycal::cli::RunProbeExtract},
      {"probe-predict", "predict the gray diffuse probe (irradiance, ball radiance, SH-9) from a preset", &skycal::cli::RunProbePredict},
      {"bench", "run time against error per setting (Pareto plots), numerical stress, --compare two runs", &skycal::cli::RunBench},
      {"report", "one self-contained HTML report (images, plots) of fit, export and bench outputs", &skycal::cli::RunReport},
      {"sun", "the sun's position (zenith, azimuth, lat-long direction) for a place and time", &skycal::cli::RunSun},
      {"weather", "a procedural weather map for the clouds (coverage, precipitation, type) as an RGB EXR", &skycal::cli::RunWeather},
  };
  return verbs;
}

bool IsHeavyVerb(const char* verb) {
  for (const char* v : {"calibrate", "fit", "render", "bench", "ceiling"})
    if (!std::strcmp(verb, v)) return true;
  return false;
}

void PrintUsage() {
  std::cout << "skycal " << skycal::kSkycalVersion << ": calibration and fitting workbench for real-time game skies\n\n"
            << "usage: skycal VERB [options]   (skycal VERB --help for a verb's options)\n\nverbs:\n";
  for (const Verb& v : Verbs()) std::cout << "  " << v.name << std::string(std::strlen(v.name) < 12 ? 12 - std::strlen(v.name) : 1, ' ') << v.summary << "\n";
  std::cout << "\n  --version   print the version\n"
            << "  --data-dir  print the directory of the bundled data (presets, OCIO config, tables) and its origin\n";
}

}  // namespace

int main(int argc, char** argv) {
  // First: glibc reads its tunables at start-up only. The verbs that touch hundreds of MB
  // (the cloud noise on the device, frames, fits) gain more than the second start costs
  // (the dynamic loader again, ~0.1 s); the quick ones (sun, compare, --version) do not.
  if (argc >= 2 && IsHeavyVerb(argv[1])) skycal::ReexecWithHugePages(argv);
  // Before any thread starts (lavapipe and Ceres start theirs): SIGINT/SIGTERM/SIGHUP remove
  // the run's temporaries and exit 128 + signal; SIGPIPE becomes a write error.
  skycal::InstallInterruptCleanup();
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    PrintUsage();
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::cout << "skycal " << skycal::kSkycalVersion << "\n";
    return 0;
  }
  if (!std::strcmp(argv[1], "--data-dir")) {  // "<dir>\t<origin>": SKYCAL_DATA_DIR, install or source
    std::cout << skycal::DataDir() << "\t" << skycal::DataDirOrigin() << "\n";
    return 0;
  }
  for (const Verb& v : Verbs()) {
    if (argv[1] == std::string(v.name)) return v.run(argc - 2, argv + 2);
  }
  std::cerr << "skycal: unknown verb '" << argv[1] << "'\n\n";
  PrintUsage();
  return 2;
}
