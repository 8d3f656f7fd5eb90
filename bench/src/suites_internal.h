// The built-in suites, one file each (private to skycal_bench; suites.cc registers them).
#pragma once
#include <string>

#include "skycal/bench/suite.h"

namespace skycal::bench {

Suite RenderSuite();   // render_suite.cc
Suite FitSuite();      // fit_suite.cc
Suite FitDaySuite();   // fit_day_suite.cc
Suite FitCieSuite();   // fit_cie_suite.cc
Suite FitCieStudySuite();  // fit_cie_study_suite.cc
Suite FitDecisionsSuite();  // fit_decisions_suite.cc
Suite SkySegmentationSuite();  // sky_segmentation_suite.cc
Suite WeatherInversionSuite();  // weather_inversion_suite.cc
Suite CaptureChartSuite();  // capture_chart_suite.cc
Suite CaptureStarsSuite();  // capture_stars_suite.cc
Suite FitSkiesSuite();  // fit_skies_suite.cc
Suite FitProbeSuite();  // fit_probe_suite.cc
Suite FitCloudsSuite();  // fit_clouds_suite.cc
Suite FitCloudsProcessSuite();  // fit_clouds_process_suite.cc
Suite BatchSuite();    // batch_suite.cc
Suite FitCloudStatsSuite();  // fit_cloud_stats_suite.cc
Suite FitCloudStatsGlsSuite();  // fit_cloud_stats_suite.cc
Suite CloudStatsNoiseSuite();  // cloud_stats_noise_suite.cc
Suite ProbeSuite();    // probe_suite.cc
Suite CaptureSuite();  // capture_suite.cc
Suite CaptureResponseSuite();  // capture_response_suite.cc
Suite ExportSuite();   // export_suite.cc
Suite StressSuite();   // stress_suite.cc
Suite CloudsErrorSuite();  // clouds_error_suite.cc
Suite CloudsDivergenceSuite();  // clouds_divergence_suite.cc
Suite CloudsSuite();   // clouds_suite.cc
Suite GpuSuite();      // gpu_suite.cc

// datasets/presets/default_clear.json of this checkout.
std::string DefaultPresetPath();

}  // namespace skycal::bench
