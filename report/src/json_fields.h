// Reading the fields the report needs from skycal's output JSON, with errors that name the
// file and the field ("DIR/fit.json: field 'references[0].rel_rmse': expected a number").
// Required fields throw skycal::Error; optional ones return nullopt when absent or null, and
// throw when present with the wrong type.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace skycal::report {

struct JsonAt {
  const nlohmann::json& value;
  std::string file;   // for messages
  std::string field;  // dotted path from the document's root ("" for the root)

  JsonAt Child(const std::string& key) const;  // required member (throws when absent)
  std::optional<JsonAt> Optional(const std::string& key) const;
  JsonAt Index(size_t i) const;
  std::string Where() const;  // "file: field 'path'"

  double Number() const;
  std::string String() const;
  bool Boolean() const;
  size_t Size() const;  // of an array (throws for anything else)
  void RequireObject() const;

  double Number(const std::string& key) const { return Child(key).Number(); }
  std::string String(const std::string& key) const { return Child(key).String(); }
  std::optional<double> OptionalNumber(const std::string& key) const;
  std::optional<std::string> OptionalString(const std::string& key) const;
  std::vector<double> Numbers(const std::string& key) const;  // optional array of numbers (empty when absent)
};

// Parses `path` (errors name it) and checks the root is an object.
nlohmann::json ReadJsonObject(const std::string& path);

}  // namespace skycal::report
