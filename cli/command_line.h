// A verb's command line, parsed by CLI11. Each option is registered once, with its help
// text (units, defaults); `--help` prints what CLI11 generates from those registrations,
// so the help and the parser cannot drift apart.
//
// Conventions (every verb): long options, `--name value` or `--name=value`; flags take no
// value; an option given twice is an error unless registered as repeatable; unknown options,
// stray arguments, missing values and non-finite numbers are errors that name the option.
// Parsing touches no file: paths are only collected (a fuzz harness can call the verbs'
// Parse<Verb>Args without side effects).
//
// CLI11 itself stays in command_line.cc: its header costs ~9 s of CPU per translation unit
// (gcc 12, -O3), and every verb includes this one.
#pragma once
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace skycal::cli {

// A check of one option's value text, run once CLI11 has matched the option: "" if the
// value is acceptable, else what was expected (CLI11 prefixes "--name: ").
using ValueCheck = std::function<std::string(std::string& text)>;

// One registered option, for further settings (what the registration functions return;
// owned by the VerbCommandLine, valid while it lives).
class CommandLineOption {
 public:
  explicit CommandLineOption(CLI::Option* option) : option_(option) {}
  CommandLineOption* check(ValueCheck check);         // an extra check of the value (NumberIn ...)
  CommandLineOption* group(const std::string& name);  // the help's heading; "" hides the option

 private:
  CLI::Option* option_;
};

// Thrown by parsing when -h/--help is anywhere on the command line: the generated help,
// which the verb prints (exit 0) instead of running.
class HelpRequested : public std::exception {
 public:
  explicit HelpRequested(std::string help) : help_(std::move(help)) {}
  const std::string& help() const { return help_; }
  const char* what() const noexcept override { return "help requested"; }

 private:
  std::string help_;
};

bool WantsHelp(int argc, char** argv);  // -h or --help among the arguments

class VerbCommandLine {
 public:
  // `about`: what the verb does (its first help line); `synopsis`: the usage lines;
  // `footer`: notes printed after the options (units, conventions), may be empty.
  VerbCommandLine(const std::string& verb, const std::string& about, const std::string& synopsis,
                  const std::string& footer = "");
  ~VerbCommandLine();

  // Registration. `name` is "--long-name", `metavar` the value's placeholder in the help
  // (DEG, OUT.exr). Targets must outlive Parse; they are written only when the option is given.
  CommandLineOption* Text(const std::string& name, std::string* target, const std::string& metavar,
                          const std::string& help);
  CommandLineOption* Text(const std::string& name, std::optional<std::string>* target, const std::string& metavar,
                          const std::string& help);
  // Finite numbers (nan/inf and trailing junk rejected).
  CommandLineOption* Number(const std::string& name, double* target, const std::string& metavar,
                            const std::string& help);
  CommandLineOption* Number(const std::string& name, std::optional<double>* target, const std::string& metavar,
                            const std::string& help);
  // An integer (written as a number: 64, 1e2) in [lo, hi]; `expected` is the message otherwise.
  CommandLineOption* Integer(const std::string& name, int* target, double lo, double hi, const std::string& expected,
                             const std::string& metavar, const std::string& help);
  CommandLineOption* Flag(const std::string& name, bool* target, const std::string& help);
  // May be given any number of times; the values collect in order.
  CommandLineOption* Repeatable(const std::string& name, std::vector<std::string>* target, const std::string& metavar,
                                const std::string& help);

  // Takes every following argument up to the next option (`--brackets a.jpg b.jpg`); may
  // also be repeated. The values collect in order.
  CommandLineOption* List(const std::string& name, std::vector<std::string>* target, const std::string& metavar,
                          const std::string& help);

  // Parses the arguments after the verb. Throws HelpRequested (help asked for) or
  // skycal::Error (a message naming the option at fault).
  void Parse(int argc, char** argv);
  std::string Help() const;

 private:
  std::string ExplainMismatch(int argc, char** argv, const std::string& cli11_message) const;

  CommandLineOption* Registered(CLI::Option* option);

  std::unique_ptr<CLI::App> app_;
  std::vector<std::unique_ptr<CommandLineOption>> options_;
};

// Checks for CommandLineOption::check. The messages follow "--name: " (CLI11 adds the name).
ValueCheck FiniteNumber();
// A finite number in [lo, hi]; `expected` says so in the option's terms ("expected g in [0, 0.999]").
ValueCheck NumberIn(double lo, double hi, const std::string& expected);
// An integer (written as a number: 64, 1e2) in [lo, hi].
ValueCheck IntegerIn(double lo, double hi, const std::string& expected);

}  // namespace skycal::cli
