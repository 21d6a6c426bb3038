#pragma once
// The settings of a form-factor computation as data: one row per setting of
// FormFactorOptions that is stored with a saved F (the settings text, format_ff_settings and
// parse_ff_settings) or reported (the form_factors section of the reports,
// ff_settings_report). An estimator parameter's row comes from its declaration on the
// estimator's registry entry (EstimatorParam in geometry/formfactors/formfactors.hpp): key,
// report name, kind, range and place; nothing is added here for it.
//
// The settings text is space-separated key=value pairs, e.g. "estimator=hybrid samples=32
// rays=1024 seed=1 threshold=0 hemicube_res=128 reciprocity=none symmetrize=0". Saved files
// and their readers depend on it byte for byte: rows may be added, never changed.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "io/json.hpp"

namespace lambert {

/// One setting: where it is stored and reported, how it is written and read back.
struct FormFactorSetting {
  /// When a setting is stored in the text and reported (else reported as null). The text
  /// lists the settings by group in this order, each group in table order (keys are only
  /// ever appended, for older readers); reports list them in table order.
  enum class When {
    Always,     ///< stored always; reported when the estimator is known (not a foreign file)
    Extended,   ///< F holds specular paths (contents.extended)
    Estimator,  ///< the estimator is one of `estimators` (an estimator parameter: analytic's tol)
    Medium,     ///< F holds a participating medium's zones (contents.medium_zones > 0)
    Resolved,   ///< the estimator was resolved from "auto" (estimator_requested not empty)
  };
  /// How the value is written and what reading it back accepts.
  enum class Kind {
    Word,      ///< as is: one of `choices`, or any nonempty word when there are none
    Integer,   ///< decimal, in [min, max]
    Unsigned,  ///< decimal, any 64-bit unsigned value
    Real,      ///< %.17g (reads back to the same double); finite, and > 0 when `positive`
    Flag,      ///< 1 or 0 (reports: true or false)
  };

  const char* key;   ///< key in the settings text ("": reported only)
  const char* name;  ///< name in the reports ("": stored only)
  When when;
  Kind kind;
  /// parse_ff_settings refuses a text without a well-formed value (another tool's text).
  bool required = false;
  std::int64_t min = 0, max = 0;  ///< Integer: the accepted range
  bool positive = false;          ///< Real: zero and negative values are refused
  /// Word: the accepted values (empty: any nonempty word).
  std::vector<std::string> choices = {};
  /// The value a text without this key means (files older than the key), or nullptr: the
  /// options keep theirs.
  const char* absent = nullptr;
  /// A legacy key of the setting keyed `yields_to`: checked, but ignored where that key is
  /// given (symmetrize= before reciprocity=).
  const char* yields_to = nullptr;
  /// The estimator parameter the row stores (its option, "--samples"; "" = none) and the
  /// estimators that declare it (When::Estimator: the row applies to them).
  std::string param = {};
  std::vector<std::string> estimators = {};

  /// The value as stored.
  std::function<std::string(const FormFactorOptions&)> text = nullptr;
  /// The value as reported.
  std::function<Json(const FormFactorOptions&)> value = nullptr;
  /// Stores a well-formed value into the options; false (options unspecified) otherwise.
  bool (*read)(const FormFactorSetting&, const std::string&, FormFactorOptions&) = nullptr;
};

/// Every stored or reported setting, in report order.
const std::vector<FormFactorSetting>& form_factor_settings();

/// Whether `setting` is stored and reported for `options` (FormFactorSetting::When).
bool setting_applies(const FormFactorSetting& setting, const FormFactorOptions& options);

/// The settings text of a computation: key=value for every row with a key that applies,
/// separated by single spaces (estimator and reciprocity resolved, never "auto", when they
/// come from a computation; symmetrize repeats reciprocity for older readers). Writers may
/// append more pairs (patches, max_edge).
std::string format_ff_settings(const FormFactorOptions& options);

/// Recovers the stored settings from a settings text into `options` (other members
/// untouched; unknown keys and words without '=' ignored). Returns false, leaving `options`
/// unchanged, when a required setting (estimator, samples, seed, threshold) is missing or
/// malformed (a file written by another tool; of a repeated required key the last counts) or
/// any other key's value is malformed or out of its range. A key that is absent keeps the
/// option's value (hemicube_res and rays: files before these were always stored wrote
/// hemicube_res for the hemicube only, and predate gather), except reciprocity: read from
/// reciprocity=, else symmetrize=, else "none" (files before these keys were always stored
/// wrote symmetrize for the hemicube only; the other estimators are reciprocal).
bool parse_ff_settings(const std::string& text, FormFactorOptions& options);

/// The reported settings: name -> value for every row with a name, in table order, null
/// where the row does not apply or (rows stored always) the estimator is unknown (empty).
Json ff_settings_report(const FormFactorOptions& options);

}  // namespace lambert
