// bench_fit --decisions [DIR]: what each of the fit's skip decisions saves, measured by
// switching it off through FitOptions on 3 skies of 512x256 from the default preset
// (fit_decision_table.h): bench/results/fit_decisions.md + .json, the numbers
// fit/src/fit_decisions.cc quotes in fit.json's `decisions`.
//
// The rest of the study this program ran is now `skycal bench` suites (one way to measure):
// the 24 skies at 512x256 with their ceilings, the old coarse-to-fine path and the whole
// process (`--suite fit-skies`), the numeric-Jacobian baseline and the forced polish
// (`--suite fit`), the 24-reference day and its old path (`--suite fit-day`).
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <string>

#include "fit_decision_table.h"
#include "skycal/render/preset.h"

using namespace skycal;

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) != "--decisions") {
    std::cerr << "usage: bench_fit --decisions [DIR]   (writes DIR/fit_decisions.md and .json; default bench/results)\n"
                 "The rest of bench_fit's study is `skycal bench --suite fit-skies,fit,fit-day` (README, Benchmarks).\n";
    return 2;
  }
  const std::filesystem::path out_dir = argc > 2 ? argv[2] : std::string(SKYCAL_SOURCE_DIR) + "/bench/results";
  const auto dir = std::filesystem::temp_directory_path() / ("skycal-bench-fit-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  bench::WriteDecisionTable(render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json"),
                            dir, out_dir);
  std::filesystem::remove_all(dir);
  return 0;
}
