#include "skycal/bench/suite.h"

#include "skycal/core/error.h"

namespace skycal::bench {

const char* ToString(Outcome o) {
  switch (o) {
    case Outcome::kOk: return "ok";
    case Outcome::kClearError: return "clear_error";
    case Outcome::kNonFinite: return "non_finite";
    case Outcome::kCrash: return "crash";
  }
  return "crash";
}

Outcome ParseOutcome(const std::string& s) {
  for (Outcome o : {Outcome::kOk, Outcome::kClearError, Outcome::kNonFinite, Outcome::kCrash})
    if (s == ToString(o)) return o;
  throw Error("bench results: unknown outcome '" + s + "' (expected ok, clear_error, non_finite or crash)");
}

bool SuiteOptions::IsValid(std::string* why) const {
  if (repeat < 0 || repeat > 1000) {
    *why = "--repeat: expected an integer in [1, 1000]";
    return false;
  }
  if (warmup < 0 || warmup > 100) {
    *why = "warm-up: expected an integer in [0, 100]";
    return false;
  }
  if (scratch.empty()) {
    *why = "bench: no scratch directory";
    return false;
  }
  return true;
}

void SuiteRegistry::Add(Suite suite) {
  if (suite.name.empty() || suite.name.find(',') != std::string::npos || Find(suite.name))
    throw Error("bench: suite name '" + suite.name + "' is empty, has a comma or is taken");
  suites_.push_back(std::move(suite));
}

const Suite* SuiteRegistry::Find(const std::string& name) const {
  for (const Suite& s : suites_)
    if (s.name == name) return &s;
  return nullptr;
}

std::vector<std::string> SuiteRegistry::Names() const {
  std::vector<std::string> names;
  for (const Suite& s : suites_) names.push_back(s.name);
  return names;
}

std::vector<const Suite*> SuiteRegistry::Resolve(const std::string& comma_list) const {
  std::vector<const Suite*> out;
  size_t start = 0;
  while (start <= comma_list.size()) {
    const size_t end = std::min(comma_list.find(',', start), comma_list.size());
    const std::string name = comma_list.substr(start, end - start);
    const Suite* s = Find(name);
    if (!s) {
      std::string valid;
      for (const std::string& n : Names()) valid += (valid.empty() ? "" : ", ") + n;
      throw Error("--suite: unknown suite '" + name + "' (valid: " + valid + ")");
    }
    for (const Suite* seen : out)
      if (seen == s) throw Error("--suite: '" + name + "' given twice");
    out.push_back(s);
    start = end + 1;
  }
  return out;
}

}  // namespace skycal::bench
