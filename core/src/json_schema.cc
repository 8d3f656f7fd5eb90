#include "skycal/core/json_schema.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "skycal/core/error.h"

namespace skycal {

std::string JsonField(const std::string& origin, const std::string& field) { return origin + ": field '" + field + "'"; }

namespace {

// Optimal string alignment distance (Damerau-Levenshtein without repeated edits of a
// substring): a swapped pair of letters counts as one typo, as a user makes it.
size_t EditDistance(const std::string& a, const std::string& b) {
  const size_t n = a.size(), m = b.size();
  std::vector<std::vector<size_t>> d(n + 1, std::vector<size_t>(m + 1));
  for (size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (size_t i = 1; i <= n; ++i) {
    for (size_t j = 1; j <= m; ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

}  // namespace

std::string NearestName(const std::string& key, const std::vector<std::string>& names) {
  if (key.size() > 256) return "";  // not a typo of any of our names; bounded work on hostile input
  std::string best;
  size_t best_d = std::max<size_t>(2, key.size() / 3) + 1;
  for (const std::string& n : names) {
    size_t d = EditDistance(key, n);
    // A key that is a prefix of a name ("haziness" for "haziness_g") is the same intent.
    if (n.size() > key.size() && key.size() >= 4 && n.compare(0, key.size(), key) == 0) d = std::min<size_t>(d, 1);
    if (d < best_d) best_d = d, best = n;
  }
  return best;
}

void RequireKnownKeys(const nlohmann::json& object, const std::vector<std::string>& allowed, const std::string& origin,
                      const std::string& prefix) {
  if (!object.is_object()) {
    const std::string where = prefix.empty() ? origin + ": the document" : JsonField(origin, prefix.substr(0, prefix.size() - 1));
    throw Error(where + ": expected a JSON object, got " + std::string(object.type_name()));
  }
  for (auto it = object.begin(); it != object.end(); ++it) {
    if (std::find(allowed.begin(), allowed.end(), it.key()) != allowed.end()) continue;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    const std::string nearest = NearestName(it.key(), allowed);
    throw Error(JsonField(origin, prefix + it.key()) + ": unknown key (" +
                (nearest.empty() ? std::string() : "did you mean '" + nearest + "'? ") + "expected one of " + list + ")");
  }
}

void RequireFormatVersion(const nlohmann::json& doc, int expected, const std::string& origin, const std::string& remedy) {
  const std::string field = JsonField(origin, "format_version");
  if (!doc.is_object() || !doc.contains("format_version")) {
    throw Error(field + " is missing: expected " + std::to_string(expected) + " (" + remedy + ")");
  }
  const nlohmann::json& v = doc.at("format_version");
  if (!v.is_number_integer()) throw Error(field + ": expected the integer " + std::to_string(expected) + ", got " + v.dump());
  const long long got = v.get<long long>();
  if (got != expected) {
    throw Error(field + ": this skycal reads version " + std::to_string(expected) + ", the file is version " +
                std::to_string(got) + (got > expected ? " (written by a newer skycal: update skycal)" : " (" + remedy + ")"));
  }
}

}  // namespace skycal
