// CIE S 011 / ISO 15469 standard general sky: table reader and luminance distribution.
// Formula and symbols: see cie_sky.h.
#include "skycal/refsky/cie_sky.h"

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"

namespace skycal::refsky {
namespace {

// Splits one CSV record (RFC 4180 subset: fields optionally in double quotes, "" inside
// quotes is a literal quote, no line breaks inside fields).
std::vector<std::string> SplitCsvLine(const std::string& line, const std::string& where) {
  std::vector<std::string> fields;
  std::string cur;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (quoted) {
      if (ch == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (ch == '"') {
        quoted = false;
      } else {
        cur += ch;
      }
    } else if (ch == '"') {
      quoted = true;
    } else if (ch == ',') {
      fields.push_back(cur);
      cur.clear();
    } else if (ch != '\r') {
      cur += ch;
    }
  }
  if (quoted) throw Error(where + ": unterminated quoted field");
  fields.push_back(cur);
  return fields;
}

double ParseNumber(const std::string& text, const std::string& where, const char* column) {
  size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v)) {
    throw Error(where + ": column '" + column + "' is '" + text + "', expected a finite number");
  }
  return v;
}

}  // namespace

std::string DefaultCieCsvPath() { return DataPath("datasets/tables/cie_general_sky.csv"); }

std::vector<CieSkyType> LoadCieSkyTypes(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw Error(path + ": cannot open the CIE standard general sky table (the data directory is " + DataDir() +
                ", from " + DataDirOrigin() + ")");
  }
  const char* kHeader[] = {"sky_type", "gradation_group", "indicatrix_group", "a", "b", "c", "d", "e", "description"};
  std::string line;
  if (!std::getline(in, line)) throw Error(path + ": empty file, expected the CIE sky table header");
  const auto header = SplitCsvLine(line, path + ":1");
  if (header.size() != 9) throw Error(path + ":1: expected 9 columns (sky_type .. description)");
  for (size_t i = 0; i < 9; ++i) {
    if (header[i] != kHeader[i]) throw Error(path + ":1: column " + std::to_string(i + 1) + " is '" + header[i] +
                                             "', expected '" + kHeader[i] + "'");
  }
  std::vector<CieSkyType> types;
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const std::string where = path + ":" + std::to_string(line_no);
    const auto f = SplitCsvLine(line, where);
    if (f.size() != 9) throw Error(where + ": " + std::to_string(f.size()) + " columns, expected 9");
    CieSkyType t;
    const double type = ParseNumber(f[0], where, "sky_type");
    if (type != std::floor(type) || type < 1 || type > 15) throw Error(where + ": sky_type must be an integer 1..15");
    t.type = static_cast<int>(type);
    t.gradation_group = f[1];
    t.indicatrix_group = f[2];
    t.a = ParseNumber(f[3], where, "a");
    t.b = ParseNumber(f[4], where, "b");
    t.c = ParseNumber(f[5], where, "c");
    t.d = ParseNumber(f[6], where, "d");
    t.e = ParseNumber(f[7], where, "e");
    t.description = f[8];
    if (!(t.b < 0.0)) throw Error(where + ": b = " + f[4] + ", expected b < 0 (phi -> 1 at the horizon)");
    if (static_cast<int>(types.size()) + 1 != t.type) {
      throw Error(where + ": sky_type " + f[0] + " out of order, expected " + std::to_string(types.size() + 1));
    }
    types.push_back(t);
  }
  if (types.size() != 15) throw Error(path + ": " + std::to_string(types.size()) + " sky types, expected 15");
  return types;
}

double CieGradation(const CieSkyType& s, double cos_zenith) {
  // Horizon and below: b / cos Z -> -inf (b < 0), exp -> 0, phi -> 1. Also avoids
  // b / (-0.0) = +inf.
  if (!(cos_zenith > 0.0)) return 1.0;
  return 1.0 + s.a * std::exp(s.b / cos_zenith);
}

double CieIndicatrix(const CieSkyType& s, double chi) {
  const double cc = std::cos(chi);
  return 1.0 + s.c * (std::exp(s.d * chi) - std::exp(s.d * std::numbers::pi / 2.0)) + s.e * cc * cc;
}

double CieRelativeLuminance(const CieSkyType& s, double view_zenith, double sun_zenith, double chi) {
  // cos(pi/2) in double is 6e-17, not 0: treat Z >= pi/2 as the horizon exactly.
  const double cos_z = view_zenith >= std::numbers::pi / 2.0 ? 0.0 : std::cos(view_zenith);
  return CieIndicatrix(s, chi) * CieGradation(s, cos_z) / (CieIndicatrix(s, sun_zenith) * CieGradation(s, 1.0));
}

double CieRelativeLuminance(const CieSkyType& s, const std::array<double, 3>& v, const std::array<double, 3>& sun) {
  // Angles by atan2 of |cross| and dot: accurate near 0 where acos is not.
  const double cx = v[1] * sun[2] - v[2] * sun[1], cy = v[2] * sun[0] - v[0] * sun[2], cz = v[0] * sun[1] - v[1] * sun[0];
  const double chi = std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2]);
  const double sun_zenith = std::atan2(std::hypot(sun[0], sun[2]), sun[1]);
  return CieIndicatrix(s, chi) * CieGradation(s, v[1]) / (CieIndicatrix(s, sun_zenith) * CieGradation(s, 1.0));
}

}  // namespace skycal::refsky
