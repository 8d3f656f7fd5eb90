#include "command_line.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include <CLI/CLI.hpp>

#include "skycal/core/error.h"

namespace skycal::cli {
namespace {

// The help's layout: what the verb does, then its usage lines (ours, not CLI11's generic
// "Usage: NAME [OPTIONS]"), then the options CLI11 lists from the registrations, then notes.
class VerbHelpFormatter : public CLI::Formatter {
 public:
  explicit VerbHelpFormatter(std::string synopsis) : synopsis_(std::move(synopsis)) {}
  std::string make_usage(const CLI::App*, std::string) const override { return "\n" + synopsis_ + "\n"; }

 private:
  std::string synopsis_;
};

// Parses the whole of `text` as a finite double.
bool ParseFinite(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(*value);
}

CLI::Validator AsValidator(ValueCheck check) { return CLI::Validator(std::move(check), ""); }

// "--name=value" -> "--name"; anything else unchanged.
std::string OptionNameOf(const std::string& token) { return token.substr(0, token.find('=')); }

}  // namespace

bool WantsHelp(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) return true;
  }
  return false;
}

ValueCheck FiniteNumber() {
  return [](std::string& text) -> std::string {
    double v;
    return ParseFinite(text, &v) ? std::string() : "expected a finite number, got '" + text + "'";
  };
}

ValueCheck NumberIn(double lo, double hi, const std::string& expected) {
  return [lo, hi, expected](std::string& text) -> std::string {
    double v;
    if (!ParseFinite(text, &v)) return "expected a finite number, got '" + text + "'";
    return v >= lo && v <= hi ? std::string() : expected + ", got " + text;
  };
}

ValueCheck IntegerIn(double lo, double hi, const std::string& expected) {
  return [lo, hi, expected](std::string& text) -> std::string {
    double v;
    if (!ParseFinite(text, &v)) return "expected a finite number, got '" + text + "'";
    return v == std::floor(v) && v >= lo && v <= hi ? std::string() : expected + ", got " + text;
  };
}

VerbCommandLine::VerbCommandLine(const std::string& verb, const std::string& about, const std::string& synopsis,
                                 const std::string& footer)
    : app_(std::make_unique<CLI::App>(about, "skycal " + verb)) {
  app_->formatter(std::make_shared<VerbHelpFormatter>(synopsis));
  app_->get_formatter()->column_width(28);
  app_->footer(footer);
}

VerbCommandLine::~VerbCommandLine() = default;

CommandLineOption* CommandLineOption::check(ValueCheck check) {
  option_->check(AsValidator(std::move(check)));
  return this;
}

CommandLineOption* CommandLineOption::group(const std::string& name) {
  option_->group(name);
  return this;
}

CommandLineOption* VerbCommandLine::Registered(CLI::Option* option) {
  options_.push_back(std::make_unique<CommandLineOption>(option));
  return options_.back().get();
}

CommandLineOption* VerbCommandLine::Text(const std::string& name, std::string* target, const std::string& metavar,
                                         const std::string& help) {
  CLI::Option* option = app_->add_option(name, *target, help);
  option->type_name(metavar);
  return Registered(option);
}

CommandLineOption* VerbCommandLine::Text(const std::string& name, std::optional<std::string>* target,
                                         const std::string& metavar, const std::string& help) {
  CLI::Option* option =
      app_->add_option_function<std::string>(name, [target](const std::string& v) { *target = v; }, help);
  option->type_name(metavar);
  return Registered(option);
}

CommandLineOption* VerbCommandLine::Number(const std::string& name, double* target, const std::string& metavar,
                                           const std::string& help) {
  CLI::Option* option = app_->add_option(name, *target, help);
  option->type_name(metavar)->check(AsValidator(FiniteNumber()));
  return Registered(option);
}

CommandLineOption* VerbCommandLine::Number(const std::string& name, std::optional<double>* target,
                                           const std::string& metavar, const std::string& help) {
  CLI::Option* option = app_->add_option_function<double>(name, [target](const double& v) { *target = v; }, help);
  option->type_name(metavar)->check(AsValidator(FiniteNumber()));
  return Registered(option);
}

CommandLineOption* VerbCommandLine::Integer(const std::string& name, int* target, double lo, double hi,
                                            const std::string& expected, const std::string& metavar,
                                            const std::string& help) {
  // Read as a double (so 1e2 counts as 100, as the number options do); the validator has
  // checked it is an integer in [lo, hi] before the cast.
  CLI::Option* option =
      app_->add_option_function<double>(name, [target](const double& v) { *target = static_cast<int>(v); }, help);
  option->type_name(metavar)->check(AsValidator(IntegerIn(lo, hi, expected)));
  return Registered(option);
}

CommandLineOption* VerbCommandLine::Flag(const std::string& name, bool* target, const std::string& help) {
  // CLI11's flags take the last of repeats and accept --flag=false: ours are given once, bare.
  CLI::Option* option = app_->add_flag(name, *target, help);
  option->multi_option_policy(CLI::MultiOptionPolicy::Throw)->disable_flag_override();
  return Registered(option);
}

CommandLineOption* VerbCommandLine::Repeatable(const std::string& name, std::vector<std::string>* target,
                                               const std::string& metavar, const std::string& help) {
  // One value per occurrence (`--reference a b` leaves `b` a stray argument, an error).
  CLI::Option* option = app_->add_option(name, *target, help);
  option->type_name(metavar)
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->allow_extra_args(false);
  return Registered(option);
}

CommandLineOption* VerbCommandLine::List(const std::string& name, std::vector<std::string>* target,
                                         const std::string& metavar, const std::string& help) {
  // A vector option's CLI11 default: one or more values per occurrence, occurrences collect.
  CLI::Option* option = app_->add_option(name, *target, help);
  option->type_name(metavar)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  return Registered(option);
}

std::string VerbCommandLine::Help() const { return app_->help(); }

void VerbCommandLine::Parse(int argc, char** argv) {
  // Help wins wherever it appears (also after a bad option), as before CLI11.
  if (WantsHelp(argc, argv)) throw HelpRequested(Help());
  std::vector<std::string> reversed(argv, argv + argc);  // CLI11 consumes from the back
  std::reverse(reversed.begin(), reversed.end());
  try {
    app_->parse(reversed);
  } catch (const CLI::ExtrasError&) {
    // Not an option of this verb, or a value with no option before it.
    std::vector<std::string> extras = app_->remaining();
    std::erase(extras, std::string("--"));  // the end-of-options marker: what follows it is stray
    for (const std::string& e : extras) {
      const bool known = app_->get_option_no_throw(OptionNameOf(e)) != nullptr;  // e.g. after a bare "--"
      if (!e.empty() && e[0] == '-' && !known) throw Error("unknown option '" + OptionNameOf(e) + "' (see --help)");
    }
    throw Error("unexpected argument '" + (extras.empty() ? std::string() : extras.front()) +
                "' (options start with --; see --help)");
  } catch (const CLI::ArgumentMismatch& e) {
    throw Error(ExplainMismatch(argc, argv, e.what()));
  } catch (const CLI::ParseError& e) {
    // Validation ("--lat: expected a finite number, got 'abc'") and conversion errors name
    // the option already.
    throw Error(e.what());
  }
}

// CLI11 reports three different mistakes as ArgumentMismatch; say which, in skycal's words.
std::string VerbCommandLine::ExplainMismatch(int argc, char** argv, const std::string& cli11_message) const {
  // A value option last on the line, or written "--name=" with nothing after the '='.
  for (int i = 0; i < argc; ++i) {
    const std::string token = argv[i];
    const bool empty_assignment = !token.empty() && token.back() == '=' && token.find('=') + 1 == token.size();
    if (i + 1 != argc && !empty_assignment) continue;
    const CLI::Option* opt = app_->get_option_no_throw(OptionNameOf(token));
    if (opt && opt->get_items_expected_min() > 0 && (empty_assignment || token.find('=') == std::string::npos)) {
      return OptionNameOf(token) + ": expected a value";
    }
  }
  // A flag given a value: --json=1.
  for (int i = 0; i < argc; ++i) {
    const std::string token = argv[i];
    if (token.find('=') == std::string::npos) continue;
    const CLI::Option* opt = app_->get_option_no_throw(OptionNameOf(token));
    if (opt && opt->get_items_expected_max() == 0) return OptionNameOf(token) + ": takes no value (a flag)";
  }
  // An option that is not repeatable, given more than once.
  for (const CLI::Option* opt : app_->get_options()) {
    if (opt->get_multi_option_policy() == CLI::MultiOptionPolicy::Throw &&
        opt->count() > static_cast<size_t>(std::max(1, opt->get_items_expected_max()))) {
      return opt->get_name() + ": given " + std::to_string(opt->count()) + " times; it is not repeatable (give it once)";
    }
  }
  return cli11_message;
}

}  // namespace skycal::cli
