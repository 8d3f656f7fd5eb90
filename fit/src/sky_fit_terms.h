// FitSky with terms added beside the sky rows, LUT priors and probe (fit_term.h): the
// entry point a new term (the cloud-lighting fit) uses without editing FitSky. Extra
// terms join every Ceres level after the built-in ones, report their skips and summaries
// into the result, and force the Ceres polish after the linear start (the linear
// structure does not hold them).
#pragma once
#include <vector>

#include "fit_term.h"
#include "skycal/fit/sky_fit.h"

namespace skycal::fit {

FitResult FitSkyWithTerms(const std::vector<Reference>& refs, const render::Preset& init, const FitOptions& options,
                          render::SkyRenderer& renderer, const std::vector<const ProbeSamples*>& probes,
                          const std::vector<FitTerm*>& extra_terms);

}  // namespace skycal::fit
