#include "skycal/bench/stress_table.h"

#include <cstdio>

namespace skycal::bench {

std::vector<StressArea> StressTable(const std::vector<CaseResult>& cases) {
  std::vector<StressArea> table;
  for (const CaseResult& c : cases) {
    if (c.suite != "stress") continue;
    std::string area = "?";
    for (const auto& [k, v] : c.settings)
      if (k == "area") area = v;
    StressArea* a = nullptr;
    for (StressArea& t : table)
      if (t.area == area) a = &t;
    if (!a) {
      table.push_back({});
      a = &table.back();
      a->area = area;
    }
    ++a->cases;
    a->ok += c.outcome == Outcome::kOk;
    a->clear_error += c.outcome == Outcome::kClearError;
    a->non_finite += c.outcome == Outcome::kNonFinite;
    a->crash += c.outcome == Outcome::kCrash;
    if (c.converged) {
      ++a->with_convergence;
      a->converged += *c.converged;
    }
  }
  return table;
}

nlohmann::json StressTableToJson(const std::vector<StressArea>& table) {
  nlohmann::json out = nlohmann::json::array();
  for (const StressArea& a : table) {
    out.push_back({{"area", a.area},
                   {"cases", a.cases},
                   {"finite_percent", a.FinitePercent()},
                   {"converged_percent", a.with_convergence ? nlohmann::json(100.0 * a.converged / a.with_convergence) : nlohmann::json()},
                   {"cases_with_convergence", a.with_convergence},
                   {"outcomes", {{"ok", a.ok}, {"clear_error", a.clear_error}, {"non_finite", a.non_finite}, {"crash", a.crash}}},
                   {"passed", a.Passed()}});
  }
  return out;
}

std::string StressTableToText(const std::vector<StressArea>& table) {
  std::string s = "| area | cases | finite % | converged % | ok | clear error | non-finite | crash |\n"
                  "|---|---|---|---|---|---|---|---|\n";
  char line[256];
  for (const StressArea& a : table) {
    char conv[32] = "-";
    if (a.with_convergence) std::snprintf(conv, sizeof conv, "%.1f (%d/%d)", 100.0 * a.converged / a.with_convergence, a.converged, a.with_convergence);
    std::snprintf(line, sizeof line, "| %s | %d | %.1f | %s | %d | %d | %d | %d |\n", a.area.c_str(), a.cases,
                  a.FinitePercent(), conv, a.ok, a.clear_error, a.non_finite, a.crash);
    s += line;
  }
  return s;
}

}  // namespace skycal::bench
