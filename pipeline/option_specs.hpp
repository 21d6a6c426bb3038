#pragma once
// Options declared once, as data: each row names an option, the values it accepts, its
// default and its one-line description. From a row come the CLI's registration, check and
// --help line (apps/options.cpp), the Python keyword's check and docstring line (python/),
// and the option reference in docs/options.md (`lambert options --markdown`, checked current
// by scripts/check_docs_options.sh). Which choice reads an option is the other table
// (pipeline/option_scope.hpp). Rows so far: the form-factor and solver options.

#include <string>
#include <vector>

namespace lambert {

/// What an option's value is.
enum class OptionKind {
  Integer,  ///< a whole number in [lo, hi]
  Real,     ///< a finite number in [lo, hi] (or open at either end)
  Choice,   ///< one of `choices`
};

/// One option's declaration.
struct OptionSpec {
  std::string name;     ///< the long name, "--samples"
  std::string keyword;  ///< the Python keyword, "samples" ("" = none)
  OptionKind kind = OptionKind::Real;
  double lo = 0.0, hi = 0.0;  ///< Integer, Real: the accepted range
  bool open_lo = false, open_hi = false;
  std::vector<std::string> choices;  ///< Choice: the accepted values
  std::string default_text;          ///< the default as --help shows it
  std::string doc;                   ///< the one-line description
};

/// The table, in the order of the reference.
const std::vector<OptionSpec>& option_specs();

/// The row of `name` ("--samples"); a missing row is a bug (LAMBERT_CHECK).
const OptionSpec& option_spec(const std::string& name);

/// A number as messages and documents show it: at most 6 significant digits ("1e-06").
std::string number_text(double x);

/// What the option accepts, for messages and documents: "an integer in [1, 1048576]",
/// "a number in (0.001, 1.999]", "one of auto, none, average".
std::string accepted_text(const OptionSpec& spec);

/// The reason `text` is not a value of `spec` ("'0' is not an integer in [1, 1048576]"),
/// empty when it is one (numbers: the whole text, finite, in range).
std::string option_value_error(const OptionSpec& spec, const std::string& text);

/// Throws UsageError "AS: REASON" when `value` is outside the option's range (Integer, Real;
/// NaN and infinities refused). `as` names the option as the caller's user knows it (the
/// Python keyword, or the option).
void check_option_value(const OptionSpec& spec, double value, const std::string& as);

/// Throws UsageError "AS: 'VALUE' is not one of ..." when `value` is not one of the choices.
void check_option_choice(const OptionSpec& spec, const std::string& value, const std::string& as);

}  // namespace lambert
