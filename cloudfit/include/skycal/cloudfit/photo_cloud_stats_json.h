// fit.json's `cloud_stats` object (fit --clouds stats) from the statistics fit's result:
// per reference the sun check, the cloud probability, the errors without and with the
// cloud statistics, the bins' medians and the panel paths; the coverage match, the fitted
// parameters, the sun scale and the solve. The fit verb adds `preset` and `sky_refit`.
// Written whole into skycal/fit/fit_result_file.h's FitResultFile::cloud_stats.
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/cloudfit/photo_cloud_stats.h"

namespace skycal::cloudfit {

nlohmann::json PhotoCloudStatsJson(const PhotoCloudStatsOptions& o, const PhotoCloudStatsResult& res);

}  // namespace skycal::cloudfit
