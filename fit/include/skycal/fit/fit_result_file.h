// fit.json at the edge: the typed FitResult (fit_report.h) as JSON. The keys are those
// fit.json has always had (`levels`, `skipped`, `linear_start`, `probe`,
// `unobserved_lut_rows`), plus `decisions`.
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/fit/sky_fit.h"

namespace skycal::fit {

nlohmann::json ToJson(const LinearStartReportOut& report);  // null when it did not run
nlohmann::json ToJson(const FitDecision& decision);
// The fit's own part of fit.json: haziness_g, time_s, iterations, termination, probe,
// linear_start, levels, skipped, decisions, unobserved_lut_rows, backend_device.
nlohmann::json FitSummaryJson(const FitResult& result);

}  // namespace skycal::fit
