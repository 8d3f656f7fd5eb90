// fit.json's `clouds` object (the cloud lighting fit with known shapes, fit --clouds: the
// decision, per parameter value / initial / unit / held and its conditioning, the cloud and
// clear pixels' errors, the solve's timing; a day's keyframes) and a day's cloud keyframes
// file (<stem>.cloud_keyframes.json), from the fit's result. Written whole into
// skycal/fit/fit_result_file.h's FitResultFile::clouds.
#pragma once
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/cloudfit/cloud_lighting_fit.h"

namespace skycal::cloudfit {

// What the fit was asked for, recorded beside the result.
struct CloudReportSettings {
  std::string mode;              // "auto", "on" or "off"
  std::string preset;            // the preset giving the known shapes ("" without)
  std::optional<double> time_s;  // the wind time of every reference, s; unset: each reference's own
  double day_smoothness = 0.0;   // the day prior's weight (relative change per h^2)
};

nlohmann::json CloudReportJson(const CloudReportSettings& settings, const SkyCloudFit& f);

// {"keys": [{time_of_day_h, reference, lighting {name: value}, cloud_pixels}], "units":
// {name: unit}}, in time order.
nlohmann::json CloudDayKeyframesJson(const SkyCloudFit& f);

}  // namespace skycal::cloudfit
