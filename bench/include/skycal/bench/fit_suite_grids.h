// The grids of the fit-probe and fit-clouds suites (fit_probe_suite.cc, fit_clouds_suite.cc),
// public so tests/bench_test.cc can check their expansion without running a fit.
#pragma once
#include "skycal/bench/grid.h"

namespace skycal::bench {

// probe (on: the default, a reference with its gray ball; off: the sky alone) x backend x
// reference size x probe weight x scenario (consistent; the ball's albedo told 5% high; the
// ground albedo held 60% low). The weights and scenarios are swept at the default size and
// backend only; the sky-only fit has neither. --quick: smaller sizes, fewer weights.
Grid FitProbeGrid(bool quick);

// sky start (the bundled clear preset, relative: what a user runs; the truth's sky,
// --absolute) x reference size x cloud samples (the Jacobian's cloud pixels). The truth's
// sky start is measured at the default size and samples only. --quick: 128x64 only.
Grid FitCloudsGrid(bool quick);

}  // namespace skycal::bench
