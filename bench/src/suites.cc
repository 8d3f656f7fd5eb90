#include "skycal/bench/suite.h"
#include "skycal/core/data_dir.h"
#include "suites_internal.h"

namespace skycal::bench {

std::string DefaultPresetPath() { return DataPath("datasets/presets/default_clear.json"); }

SuiteRegistry BuiltinSuites() {
  SuiteRegistry r;
  r.Add(RenderSuite());
  r.Add(FitSuite());
  r.Add(FitDaySuite());
  r.Add(FitCieSuite());
  r.Add(FitCieStudySuite());
  r.Add(FitDecisionsSuite());
  r.Add(FitSkiesSuite());
  r.Add(FitProbeSuite());
  r.Add(FitCloudsSuite());
  r.Add(FitCloudsProcessSuite());
  r.Add(BatchSuite());
  r.Add(FitCloudStatsSuite());
  r.Add(FitCloudStatsGlsSuite());
  r.Add(CloudStatsNoiseSuite());
  r.Add(ProbeSuite());
  r.Add(CaptureSuite());
  r.Add(SkySegmentationSuite());
  r.Add(WeatherInversionSuite());
  r.Add(CaptureChartSuite());
  r.Add(CaptureStarsSuite());
  r.Add(CaptureResponseSuite());
  r.Add(ExportSuite());
  r.Add(StressSuite());
  r.Add(GpuSuite());  // before the clouds suites: `clouds` stays last in --suite's list
  r.Add(CloudsErrorSuite());
  r.Add(CloudsDivergenceSuite());
  r.Add(CloudsSuite());
  return r;
}

}  // namespace skycal::bench
