#include "skycal/bench/suite.h"
#include "suites_internal.h"

namespace skycal::bench {

std::string DefaultPresetPath() { return std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json"; }

SuiteRegistry BuiltinSuites() {
  SuiteRegistry r;
  r.Add(RenderSuite());
  r.Add(FitSuite());
  r.Add(ProbeSuite());
  r.Add(CaptureSuite());
  r.Add(ExportSuite());
  r.Add(StressSuite());
  // Clouds (issue: volumetric clouds) registers here when its renderer and fit land:
  // r.Add(CloudsRenderSuite()); r.Add(CloudsFitSuite());  -- a Suite each, in clouds_suite.cc,
  // with step counts, light samples and each march optimisation as grid axes.
  return r;
}

}  // namespace skycal::bench
