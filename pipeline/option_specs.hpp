#pragma once
// Every option declared once, as data. A row names an option, the commands that take it with
// that meaning, the values it accepts, its default, its one-line description and what reads
// it (the method it belongs to, or a predicate over the command line's choices). From the
// rows come:
//   - the CLI's registration, check, --help line and default (apps/options.cpp, add_declared);
//   - the "does not apply to ..." refusal of an option the chosen method, estimator, solver or
//     shading does not read (pipeline/option_scope.hpp, pipeline/method.hpp);
//   - the Python keyword's check and docstring line (python/);
//   - the option reference in docs/options.md (`lambert options --markdown`, kept current by
//     scripts/check_docs_options.sh).
// Adding an option: one row here, one binding in apps/options.cpp (the field it sets). An
// estimator's parameter has neither: its rows and binding come from its declaration on the
// estimator's registry entry (EstimatorParam, geometry/formfactors/formfactors.hpp).

#include <functional>
#include <string>
#include <vector>

#include "pipeline/option_scope.hpp"

namespace lambert {

/// What an option's value is.
enum class OptionKind {
  Flag,     ///< no value
  Integer,  ///< a whole number in [lo, hi]
  Real,     ///< a finite number in [lo, hi] (or open at either end; hi = inf: no bound)
  Choice,   ///< one of `choices`
  Text,     ///< text that `check` accepts (a file, a size, R,G,B, ...); `value_name` says what
};

/// One option's declaration.
struct OptionSpec {
  std::string name;  ///< the long name, "--samples"
  /// The commands that take the option with this row's meaning; empty = every command that
  /// registers it and has no row of its own (`run` has its own --samples: a cheaper default).
  std::vector<std::string> commands;
  std::string group;    ///< "scene", "form factors", "solver", "medium", ... (the reference)
  std::string keyword;  ///< the Python keyword, "samples" ("" = none)
  OptionKind kind = OptionKind::Text;
  double lo = 0.0, hi = 0.0;  ///< Integer, Real: the accepted range
  bool open_lo = false, open_hi = false;
  std::vector<std::string> choices;  ///< Choice: the accepted values
  std::string value_name;            ///< Text: what the value is ("FILE", "R,G,B", "SIZE")
  /// Text: the reason a value is refused ("" = accepted); empty function = any text.
  std::function<std::string(const std::string&)> check;
  int count = 1;             ///< values per use (--eye X Y Z: 3); 0 = any number (a list)
  char delimiter = 0;        ///< ',' when the values come as one comma-separated word
  std::string default_text;  ///< the default as --help shows it ("" = none or computed)
  std::string doc;           ///< the one-line description
  /// The method whose option it is ("" = every method). `method_solver`: it steers that
  /// method's solve (solver options) rather than the problem (meshing, F).
  std::string method;
  bool method_solver = false;
  /// What reads it (for refusals and the reference), and when: an option given on a command
  /// line whose choices it does not read is a usage error. Empty `reads`: every choice of
  /// the commands that take it (and of its `method`).
  std::string reader;
  std::function<bool(const Selection&)> reads;
};

/// The table, grouped as the reference lists it.
const std::vector<OptionSpec>& option_specs();

/// The row of `name` ("--samples") for `command` ("" = the row for every command); a
/// missing row is a bug (LAMBERT_CHECK).
const OptionSpec& option_spec(const std::string& name, const std::string& command = "");

/// The row of `name` for `command`, or nullptr when there is none.
const OptionSpec* find_option_spec(const std::string& name, const std::string& command);

/// What reads the option, for the reference: its reader, "--method M", or "every choice".
std::string reader_text(const OptionSpec& spec);

/// The options of `group` (their long names, in table order, once each).
std::vector<std::string> option_group(const std::string& group);

/// A number as messages and documents show it: at most 6 significant digits ("1e-06").
std::string number_text(double x);

/// What the option accepts, for messages and documents: "an integer in [1, 1048576]",
/// "a number in (0.001, 1.999]", "one of auto, none, average", "3 numbers", "flag".
std::string accepted_text(const OptionSpec& spec);

/// The reason `text` is not a value of `spec` ("'0' is not an integer in [1, 1048576]"),
/// empty when it is one (numbers: the whole text, finite, in range). One value of a list.
std::string option_value_error(const OptionSpec& spec, const std::string& text);

/// Throws UsageError "AS: REASON" when `value` is outside the option's range (Integer, Real;
/// NaN and infinities refused). `as` names the option as the caller's user knows it (the
/// Python keyword, or the option).
void check_option_value(const OptionSpec& spec, double value, const std::string& as);

/// Throws UsageError "AS: 'VALUE' is not one of ..." when `value` is not one of the choices.
void check_option_choice(const OptionSpec& spec, const std::string& value, const std::string& as);

/// The checks of file options: an output file whose directory exists; an output prefix (a
/// name ending in '/' is a directory, created when writing); an existing input file.
std::string output_file_error(const std::string& path);
std::string output_prefix_error(const std::string& path);
std::string input_file_error(const std::string& path);

}  // namespace lambert
