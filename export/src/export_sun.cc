#include "skycal/export/export_sun.h"

#include <nlohmann/json.hpp>

#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"

namespace skycal::exporter {

SunSource SunFromProvenance(const std::string& path) {
  SunSource s;
  const nlohmann::json j = ReadJsonFile(path);
  if (!j.contains("provenance")) {
    s.reason = "no provenance in " + path + " (not written by skycal fit): sun direction unknown";
    return s;
  }
  const nlohmann::json& pv = j["provenance"];
  if (!pv.is_object() || !pv.contains("final_errors") || !pv["final_errors"].is_array() || pv["final_errors"].empty()) {
    s.reason = "provenance in " + path + " has no final_errors: sun direction unknown";
    return s;
  }
  const nlohmann::json& d = pv["final_errors"][0].value("sun_direction", nlohmann::json());
  if (!d.is_array() || d.size() != 3 || !d[0].is_number() || !d[1].is_number() || !d[2].is_number()) {
    s.reason = "provenance.final_errors[0].sun_direction in " + path + " is missing or not 3 numbers";
    return s;
  }
  try {
    s.dir = latlong::Normalized({d[0].get<double>(), d[1].get<double>(), d[2].get<double>()}, "sun direction");
  } catch (const Error& e) {
    s.reason = path + ": provenance.final_errors[0].sun_direction: " + e.what();
    return s;
  }
  s.known = true;
  s.source = "provenance.final_errors[0].sun_direction";
  if (pv["final_errors"].size() > 1) s.source += " (first of " + std::to_string(pv["final_errors"].size()) + " references)";
  return s;
}

}  // namespace skycal::exporter
