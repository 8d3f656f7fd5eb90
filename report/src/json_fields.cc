#include "json_fields.h"

#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/json_schema.h"

namespace skycal::report {

std::string JsonAt::Where() const { return field.empty() ? file : JsonField(file, field); }

void JsonAt::RequireObject() const {
  if (!value.is_object()) throw Error(Where() + ": expected an object");
}

JsonAt JsonAt::Child(const std::string& key) const {
  RequireObject();
  const std::string path = field.empty() ? key : field + "." + key;
  const auto it = value.find(key);
  if (it == value.end()) throw Error(JsonField(file, path) + ": missing");
  return {*it, file, path};
}

std::optional<JsonAt> JsonAt::Optional(const std::string& key) const {
  RequireObject();
  const auto it = value.find(key);
  if (it == value.end() || it->is_null()) return std::nullopt;
  return JsonAt{*it, file, field.empty() ? key : field + "." + key};
}

JsonAt JsonAt::Index(size_t i) const {
  if (!value.is_array() || i >= value.size()) throw Error(Where() + ": expected an array of more than " + std::to_string(i) + " elements");
  return {value[i], file, field + "[" + std::to_string(i) + "]"};
}

double JsonAt::Number() const {
  if (!value.is_number()) throw Error(Where() + ": expected a number, found " + std::string(value.type_name()));
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw Error(Where() + ": expected a finite number");
  return v;
}

std::string JsonAt::String() const {
  if (!value.is_string()) throw Error(Where() + ": expected a string, found " + std::string(value.type_name()));
  return value.get<std::string>();
}

bool JsonAt::Boolean() const {
  if (!value.is_boolean()) throw Error(Where() + ": expected true or false, found " + std::string(value.type_name()));
  return value.get<bool>();
}

size_t JsonAt::Size() const {
  if (!value.is_array()) throw Error(Where() + ": expected an array, found " + std::string(value.type_name()));
  return value.size();
}

std::optional<double> JsonAt::OptionalNumber(const std::string& key) const {
  const auto c = Optional(key);
  if (!c) return std::nullopt;
  return c->Number();
}

std::optional<std::string> JsonAt::OptionalString(const std::string& key) const {
  const auto c = Optional(key);
  if (!c) return std::nullopt;
  return c->String();
}

std::vector<double> JsonAt::Numbers(const std::string& key) const {
  std::vector<double> out;
  const auto c = Optional(key);
  if (!c) return out;
  for (size_t i = 0; i < c->Size(); ++i) out.push_back(c->Index(i).Number());
  return out;
}

nlohmann::json ReadJsonObject(const std::string& path) {
  nlohmann::json j = ReadJsonFile(path);
  if (!j.is_object()) throw Error(path + ": expected a JSON object at the top level");
  return j;
}

}  // namespace skycal::report
