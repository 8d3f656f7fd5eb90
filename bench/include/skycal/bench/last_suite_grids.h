// The grids of the suites that replaced the last measuring programs and scripts outside
// `skycal bench` (fit-decisions: `bench_fit --decisions`; fit-clouds-process:
// bench/fit_clouds.sh), public so tests/bench_test.cc can check them without running them.
#pragma once
#include <string>
#include <vector>

#include "skycal/bench/grid.h"

namespace skycal::bench {

// One axis, `variant`: the fit's options and start for each measured configuration --
//   default               the default FitOptions from the default preset (every skip on)
//   polish                the Ceres polish forced after the linear start (--polish)
//   polish+coarse-levels  the polish, and the coarse pyramid levels not skipped
//   overcast0.2           default options from the preset with overcast_weight 0.2
//   overcast0.2+lz-free   the same, L_z not held in ffxv-iso
// Each case fits every sky of `width` x width/2 (`runs` timed repeats per sky).
struct FitDecisionsPlan {
  Grid grid;
  int width = 512;
  int runs = 3;
};
FitDecisionsPlan FitDecisionsGridPlan(bool quick);

// One skip decision: the variant with it (on) and the one with it switched off (off).
struct DecisionSwitch {
  std::string row;   // short name (fit/src/fit_decisions.cc quotes it)
  std::string what;  // the table's description
  std::string on, off;
};
const std::vector<DecisionSwitch>& DecisionSwitches();

// fit-clouds-process: `skycal fit --clouds on --cloud-preset <bundled cloudy>` as a user runs
// it (one whole process, start-up and files included) on one cloudy reference rendered from
// the bundled cloudy preset (sun 30 deg, azimuth 40 deg) at `width` x width/2. Axis `start`:
// relative (from the bundled clear preset: the default) or absolute (--init <the cloudy
// preset> --absolute: the reference's own sky, the truth).
struct FitCloudsProcessPlan {
  Grid grid;
  int width = 512;
};
FitCloudsProcessPlan FitCloudsProcessGridPlan(bool quick);

// batch: `skycal batch` on a synthetic day (`frames` frames of width x width/2 every
// 24/frames h, the sun of 70 deg N at the June solstice: always above the horizon), rendered
// (cpu) from a perturbed default preset and fitted from the default preset, --jobs `jobs`,
// `frames_per_job` per chunk. Axis `run`: warm (the default), cold (--cold-start),
// warm-ceres / cold-ceres (--no-linear-start), slurm (the warm run on a single-node cluster
// started by tests/slurm_cluster.sh; root only, otherwise a clear "skipped: why" case).
struct BatchPlan {
  Grid grid;
  int frames = 96, width = 128, jobs = 2, frames_per_job = 8;
};
BatchPlan BatchGridPlan(bool quick);
// The sun of 70 deg N at the June solstice at hour h (solar time): elevation, azimuth (deg).
void BatchDaySun(double hour, double* elevation_deg, double* azimuth_deg);

}  // namespace skycal::bench
