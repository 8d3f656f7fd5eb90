#include "skycal/bench/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

#include "skycal/core/error.h"

namespace skycal::bench {
namespace {

double Spread(const Timing& t) { return t.median_ms > 0.0 ? (t.max_ms - t.min_ms) / t.median_ms : 0.0; }

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

std::string FormatMs(double ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", ms);
  return buf;
}

}  // namespace

bool CompareOptions::IsValid(std::string* why) const {
  if (!(noise_floor >= 0.0 && noise_floor < 10.0) || !(error_tolerance >= 0.0 && error_tolerance < 10.0)) {
    *why = "compare: noise floor and error tolerance must be in [0, 10)";
    return false;
  }
  return true;
}

const char* ToString(Verdict v) {
  switch (v) {
    case Verdict::kSame: return "same";
    case Verdict::kSlower: return "SLOWER";
    case Verdict::kFaster: return "faster";
    case Verdict::kOnlyOld: return "only in old";
    case Verdict::kOnlyNew: return "only in new";
  }
  return "?";
}

Comparison Compare(const Results& old_run, const Results& new_run, const CompareOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  Comparison out;
  out.old_commit = old_run.machine.commit;
  out.new_commit = new_run.machine.commit;
  std::map<std::pair<std::string, std::string>, const CaseResult*> old_cases;
  for (const CaseResult& c : old_run.cases) old_cases[{c.suite, c.name}] = &c;
  std::map<std::pair<std::string, std::string>, bool> matched;
  for (const CaseResult& n : new_run.cases) {
    CaseComparison cc;
    cc.suite = n.suite;
    cc.name = n.name;
    cc.new_ms = n.time.median_ms;
    cc.new_error = n.error;
    cc.new_outcome = ToString(n.outcome);
    const auto it = old_cases.find({n.suite, n.name});
    if (it == old_cases.end()) {
      cc.verdict = Verdict::kOnlyNew;
      cc.old_error = std::nan("");
      out.cases.push_back(cc);
      continue;
    }
    matched[it->first] = true;
    const CaseResult& p = *it->second;
    cc.old_ms = p.time.median_ms;
    cc.old_error = p.error;
    cc.old_outcome = ToString(p.outcome);
    cc.noise = std::max({Spread(p.time), Spread(n.time), o.noise_floor});
    // An old median of 0 (a case too fast to time then) against a measurable new one is
    // an unbounded slowdown, not "same": ratio +inf. Both 0: the same.
    cc.ratio = p.time.median_ms > 0.0   ? n.time.median_ms / p.time.median_ms
               : n.time.median_ms > 0.0 ? std::numeric_limits<double>::infinity()
               : n.time.median_ms == 0.0 && p.time.median_ms == 0.0 ? 1.0
                                                                      : std::nan("");
    // Untimed cases (stress: one run each, the input's outcome is what matters) get no time verdict.
    const bool timed = p.timed && n.timed;
    if (timed && cc.ratio > 1.0 + cc.noise) cc.verdict = Verdict::kSlower;  // NaN compares false
    else if (timed && std::isfinite(cc.ratio) && cc.ratio < 1.0 / (1.0 + cc.noise)) cc.verdict = Verdict::kFaster;
    // Error: worse beyond the relative tolerance (plus a tiny absolute floor for ~0 errors),
    // or a number that became non-finite.
    if (std::isfinite(p.error)) {
      cc.error_worse = !std::isfinite(n.error) || n.error > p.error * (1.0 + o.error_tolerance) + 1e-12;
    }
    out.slower += cc.verdict == Verdict::kSlower;
    out.faster += cc.verdict == Verdict::kFaster;
    out.error_worse += cc.error_worse;
    // Was fine, now a crash or a non-finite output.
    out.outcome_worse += (p.outcome == Outcome::kOk || p.outcome == Outcome::kClearError) &&
                         (n.outcome == Outcome::kNonFinite || n.outcome == Outcome::kCrash);
    out.cases.push_back(cc);
  }
  for (const CaseResult& p : old_run.cases) {
    if (matched.count({p.suite, p.name})) continue;
    CaseComparison cc;
    cc.suite = p.suite;
    cc.name = p.name;
    cc.old_ms = p.time.median_ms;
    cc.old_error = p.error;
    cc.new_error = std::nan("");
    cc.old_outcome = ToString(p.outcome);
    cc.verdict = Verdict::kOnlyOld;
    out.cases.push_back(cc);
  }
  return out;
}

std::string Comparison::ToText() const {
  std::ostringstream s;
  s << "old " << old_commit << " -> new " << new_commit << "\n";
  char line[512];
  std::snprintf(line, sizeof line, "%-8s %-48s %11s %11s %7s %6s  %-11s %s\n", "suite", "case", "old ms", "new ms",
                "ratio", "noise", "verdict", "error old -> new");
  s << line;
  for (const CaseComparison& c : cases) {
    if (c.verdict == Verdict::kOnlyOld || c.verdict == Verdict::kOnlyNew) {
      std::snprintf(line, sizeof line, "%-8s %-48s %11s %11s %7s %6s  %-11s\n", c.suite.c_str(), c.name.substr(0, 48).c_str(),
                    c.verdict == Verdict::kOnlyOld ? FormatMs(c.old_ms).c_str() : "-",
                    c.verdict == Verdict::kOnlyNew ? FormatMs(c.new_ms).c_str() : "-", "-", "-", ToString(c.verdict));
      s << line;
      continue;
    }
    std::snprintf(line, sizeof line, "%-8s %-48s %11.3f %11.3f %7.3f %5.0f%%  %-11s %.4g -> %.4g%s\n", c.suite.c_str(),
                  c.name.substr(0, 48).c_str(), c.old_ms, c.new_ms, c.ratio, 100.0 * c.noise, ToString(c.verdict),
                  c.old_error, c.new_error, c.error_worse ? "  ERROR WORSE" : "");
    s << line;
  }
  s << slower << " slower beyond noise, " << faster << " faster, " << error_worse << " with a worse error, "
    << outcome_worse << " newly failing\n";
  return s.str();
}

nlohmann::json Comparison::ToJson() const {
  nlohmann::json rows = nlohmann::json::array();
  for (const CaseComparison& c : cases) {
    rows.push_back({{"suite", c.suite}, {"case", c.name}, {"old_median_ms", c.old_ms}, {"new_median_ms", c.new_ms},
                    {"ratio", Number(c.ratio)}, {"noise", c.noise}, {"verdict", ToString(c.verdict)},
                    {"old_error", Number(c.old_error)}, {"new_error", Number(c.new_error)}, {"error_worse", c.error_worse},
                    {"old_outcome", c.old_outcome}, {"new_outcome", c.new_outcome}});
  }
  return {{"old_commit", old_commit}, {"new_commit", new_commit}, {"cases", rows},       {"slower", slower},
          {"faster", faster},         {"error_worse", error_worse}, {"outcome_worse", outcome_worse},
          {"regressed", Regressed()}};
}

}  // namespace skycal::bench
