// Converting option values that are more than one number ("X,Y,Z", "WxH", "A,B,C,...") into
// numbers, strictly: every piece a finite number, errors naming the option. Used after
// CLI11 has matched the option (command_line.h); no I/O.
#pragma once
#include <array>
#include <string>
#include <vector>

namespace skycal::cli {

// A finite double, the whole text consumed; throws skycal::Error
// "<option>: expected a finite number, got '<text>'". `option` is written as given ("--lat").
double ParseNumber(const std::string& text, const std::string& option);

// "X,Y,Z": exactly three finite numbers.
std::array<double, 3> ParseVec3(const std::string& text, const std::string& option);

// "WIDTHxHEIGHT": positive integers, each at most 1e6 (pixels).
std::array<int, 2> ParseSize(const std::string& text, const std::string& option);

// "A,B,C,...": one or more finite numbers.
std::vector<double> ParseNumberList(const std::string& text, const std::string& option);

// ParseNumber that also requires an integer value (written as one: 64, 1e2).
int ParseInteger(const std::string& text, const std::string& option);

}  // namespace skycal::cli
