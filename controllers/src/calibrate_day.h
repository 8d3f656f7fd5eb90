// A time-lapse's partly cloudy frames (calibrate with several photos that carry their times):
// one wind for the day (cloudfit/weather_wind.h) from the weather maps inverted from
// consecutive frames, so that one map advected by the wind serves the frames next to it;
// how far each frame's map, so moved, predicts the next frame's clouds; the wind written into
// every such frame's preset (its clouds' wind_speed and wind_direction) and DIR/day.json.
#pragma once
#include <string>

#include "skycal/controllers/calibrate.h"

namespace skycal::controllers {

inline constexpr const char* kDayWindFile = "day.json";

// Runs after the photos are calibrated and before the tables are exported (they carry the
// wind), over every photo calibrated in DIR (earlier runs' too, as the export). Frames
// qualify with an inverted weather map and a time: the EXR's capDate and
// utcOffset (capture, import), else skycalCloudTimeS (render --clouds --cloud-time); one
// source for all. Fewer than two: no DIR/day.json (an earlier one is removed), and with two
// or more partly cloudy frames the reason goes to the log and r->warnings. A failure is a warning: the frames'
// calibrations stand.
void FitTheDaysWind(const CalibrateOptions& o, CalibrateResult* r);

}  // namespace skycal::controllers
