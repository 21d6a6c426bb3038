#include "io/ff_settings.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <limits>
#include <sstream>
#include <type_traits>

#include "core/error.hpp"

namespace lambert {
// The helpers in a namespace of their own: lambert_io compiles in batches of files (unity
// builds), whose anonymous namespaces are one.
namespace settings_table {
namespace {

using Setting = FormFactorSetting;
using When = FormFactorSetting::When;
using Kind = FormFactorSetting::Kind;
using O = FormFactorOptions;

// The largest value of the int fields (counts, resolutions).
constexpr std::int64_t kIntMax = std::numeric_limits<std::int32_t>::max();

// strtoll/strtoull/strtod over the whole of `s` (the settings text's reading since its first
// files: leading '+' and, for reals, hexadecimal floats are accepted).
bool parse_int(const std::string& s, long long& v) {
  char* end = nullptr;
  errno = 0;
  v = std::strtoll(s.c_str(), &end, 10);
  return !s.empty() && *end == '\0' && errno == 0;
}
bool parse_uint(const std::string& s, std::uint64_t& v) {
  char* end = nullptr;
  errno = 0;
  v = std::strtoull(s.c_str(), &end, 10);
  return !s.empty() && s[0] != '-' && *end == '\0' && errno == 0;
}
bool parse_double(const std::string& s, double& v) {
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == '\0' && std::isfinite(v);
}

// The member of FormFactorOptions that Path leads to: member<&O::pair,
// &PairEstimatorParams::samples>(o) is o.pair.samples.
template <auto... Path>
auto& member(O& o) {
  return (o.*....*Path);
}
template <auto... Path>
const auto& member(const O& o) {
  return (o.*....*Path);
}
template <auto... Path>
using MemberType = std::remove_reference_t<decltype(member<Path...>(std::declval<O&>()))>;

// The rows of each kind: text, report value and reading of the member at Path.

template <auto... Path>
Json report(const O& o) {
  return Json(member<Path...>(o));
}

template <auto... Path>
std::string text_as_is(const O& o) {
  return member<Path...>(o);
}
template <auto... Path>
bool read_word(const Setting& s, const std::string& v, O& o) {
  member<Path...>(o) = v;
  return s.choices.empty() ? !v.empty()
                           : std::find(s.choices.begin(), s.choices.end(), v) != s.choices.end();
}
template <auto... Path>
Setting word(const char* key, const char* name, When when, std::vector<std::string> choices) {
  Setting s{key, name, when, Kind::Word};
  s.choices = std::move(choices);
  s.text = &text_as_is<Path...>;
  s.value = &report<Path...>;
  s.read = &read_word<Path...>;
  return s;
}

template <auto... Path>
std::string text_decimal(const O& o) {
  return std::to_string(member<Path...>(o));
}
template <auto... Path>
bool read_integer(const Setting& s, const std::string& v, O& o) {
  long long k = 0;
  if (!parse_int(v, k) || k < s.min || k > s.max) return false;
  member<Path...>(o) = static_cast<MemberType<Path...>>(k);
  return true;
}
template <auto... Path>
Setting integer(const char* key, const char* name, When when, std::int64_t min, std::int64_t max) {
  Setting s{key, name, when, Kind::Integer};
  s.min = min;
  s.max = max;
  s.text = &text_decimal<Path...>;
  s.value = &report<Path...>;
  s.read = &read_integer<Path...>;
  return s;
}

template <auto... Path>
bool read_unsigned(const Setting&, const std::string& v, O& o) {
  return parse_uint(v, member<Path...>(o));
}
template <auto... Path>
Setting unsigned_integer(const char* key, const char* name, When when) {
  Setting s{key, name, when, Kind::Unsigned};
  s.text = &text_decimal<Path...>;
  s.value = &report<Path...>;
  s.read = &read_unsigned<Path...>;
  return s;
}

template <auto... Path>
std::string text_exact(const O& o) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", member<Path...>(o));
  return buf;
}
template <auto... Path>
bool read_real(const Setting& s, const std::string& v, O& o) {
  double& x = member<Path...>(o);
  return parse_double(v, x) && (!s.positive || x > 0.0);
}
template <auto... Path>
Setting real(const char* key, const char* name, When when, bool positive) {
  Setting s{key, name, when, Kind::Real};
  s.positive = positive;
  s.text = &text_exact<Path...>;
  s.value = &report<Path...>;
  s.read = &read_real<Path...>;
  return s;
}

template <auto... Path>
std::string text_flag(const O& o) {
  return member<Path...>(o) ? "1" : "0";
}
template <auto... Path>
bool read_flag(const Setting&, const std::string& v, O& o) {
  member<Path...>(o) = v == "1";
  return v == "0" || v == "1";
}
template <auto... Path>
Setting flag(const char* key, const char* name, When when) {
  Setting s{key, name, when, Kind::Flag};
  s.text = &text_flag<Path...>;
  s.value = &report<Path...>;
  s.read = &read_flag<Path...>;
  return s;
}

Setting required(Setting s) {
  s.required = true;
  return s;
}

// "average" or "none": what the computation did ("auto", never stored from one, as none).
// Files before reciprocity= and symmetrize= were always stored were made without averaging.
Setting reciprocity() {
  Setting s =
      word<&O::reciprocity>("reciprocity", "reciprocity", When::Always, {"none", "average"});
  s.absent = "none";
  s.text = [](const O& o) -> std::string {
    return o.reciprocity == "average" ? "average" : "none";
  };
  return s;
}

// The older spelling of reciprocity (what readers before reciprocity= parse): a flag, not a
// member of its own.
Setting symmetrize() {
  Setting s{"symmetrize", "symmetrize", When::Always, Kind::Flag};
  s.yields_to = "reciprocity";
  s.text = [](const O& o) -> std::string { return o.reciprocity == "average" ? "1" : "0"; };
  s.value = [](const O& o) { return Json(o.reciprocity == "average"); };
  s.read = [](const Setting&, const std::string& v, O& o) {
    o.reciprocity = v == "1" ? "average" : "none";
    return v == "0" || v == "1";
  };
  return s;
}

// The specular bounces; its key in a text says that F holds the specular paths.
Setting specular_depth() {
  Setting s = integer<&O::specular, &SpecularParams::depth>("specular_depth", "specular_depth",
                                                            When::Extended, 1, 64);
  s.read = [](const Setting& row, const std::string& v, O& o) {
    if (!read_integer<&O::specular, &SpecularParams::depth>(row, v, o)) return false;
    o.contents.extended = true;
    return true;
  };
  return s;
}

// The row of an estimator parameter, from its declaration (EstimatorParam): an integer as
// decimal, a real as %.17g; read back through set_estimator_param.
Setting estimator_param_row(const DeclaredEstimatorParam& d) {
  const EstimatorParam& p = d.param;
  Setting s{"", "", p.stored_always ? When::Always : When::Estimator,
            p.integer ? Kind::Integer : Kind::Real};
  s.param = p.option;
  s.estimators = d.estimators;
  s.required = p.required;
  if (p.integer) {
    const bool stored = p.stored_min != 0.0 || p.stored_max != 0.0;
    s.min = static_cast<std::int64_t>(stored ? p.stored_min : p.lo);
    s.max = static_cast<std::int64_t>(stored ? p.stored_max : p.hi);
  } else {
    s.positive = p.lo > 0.0 || (p.lo == 0.0 && p.open_lo);
  }
  const std::string option = p.option;
  if (p.integer) {
    s.text = [option](const O& o) {
      return std::to_string(static_cast<long long>(estimator_param(o, option)));
    };
    s.value = [option](const O& o) {
      return Json(static_cast<std::int64_t>(estimator_param(o, option)));
    };
    s.read = [](const Setting& row, const std::string& v, O& o) {
      long long k = 0;
      if (!parse_int(v, k) || k < row.min || k > row.max) return false;
      set_estimator_param(o, row.param, static_cast<double>(k));
      return true;
    };
  } else {
    s.text = [option](const O& o) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", estimator_param(o, option));
      return std::string(buf);
    };
    s.value = [option](const O& o) { return Json(estimator_param(o, option)); };
    s.read = [](const Setting& row, const std::string& v, O& o) {
      double x = 0.0;
      if (!parse_double(v, x) || (row.positive && !(x > 0.0))) return false;
      set_estimator_param(o, row.param, x);
      return true;
    };
  }
  return s;
}

// The fixed rows, then each estimator parameter's after the row it names (key or report
// name; at the end when it names none). The keys and names are the rows' own strings, which
// live as long as the table (the parameters' in `keys`).
std::vector<Setting> with_estimator_params(std::vector<Setting> rows) {
  static std::deque<std::string> keys;  // the parameters' keys and names (never moved)
  for (const DeclaredEstimatorParam& d : estimator_params()) {
    Setting s = estimator_param_row(d);
    keys.push_back(d.param.key.empty() ? d.param.keyword : d.param.key);
    s.key = keys.back().c_str();
    keys.push_back(d.param.report.empty() ? d.param.keyword : d.param.report);
    s.name = keys.back().c_str();
    for (const Setting& r : rows)
      LAMBERT_CHECK(std::string(r.key) != s.key && std::string(r.name) != s.name,
                    d.param.option + ": its settings key or report name is taken");
    auto at = rows.end();
    if (!d.param.after.empty())
      at = std::find_if(rows.begin(), rows.end(), [&](const Setting& r) {
        return d.param.after == r.key || d.param.after == r.name;
      });
    LAMBERT_CHECK(d.param.after.empty() || at != rows.end(),
                  d.param.option + ": no setting '" + d.param.after + "' to follow");
    rows.insert(at == rows.end() ? at : at + 1, std::move(s));
  }
  return rows;
}

std::vector<Setting> make_settings() {
  using Contents = FormFactorContents;
  return with_estimator_params({
      required(word<&O::estimator>("estimator", "estimator", When::Always, {})),
      word<&O::estimator_requested>("", "estimator_requested", When::Resolved, {}),
      required(unsigned_integer<&O::run, &FormFactorRun::seed>("seed", "seed", When::Always)),
      required(real<&O::threshold>("threshold", "threshold", When::Always, false)),
      reciprocity(),
      symmetrize(),
      flag<&O::contents, &Contents::extended>("", "extended", When::Always),
      specular_depth(),
      integer<&O::specular, &SpecularParams::rays>("specular_rays", "specular_rays", When::Extended,
                                                   1, kIntMax),
      integer<&O::contents, &Contents::medium_zones>("medium_zones", "", When::Medium, 1, kIntMax),
      unsigned_integer<&O::contents, &Contents::medium_extinction>("medium_extinction", "",
                                                                   When::Medium),
      integer<&O::contents, &Contents::medium_rays>("medium_rays", "", When::Medium, 1, kIntMax),
      integer<&O::contents, &Contents::transmittance_samples>("transmittance_samples", "",
                                                              When::Medium, 1, kIntMax),
  });
}

// The groups of the settings text, in order.
constexpr When kTextOrder[] = {When::Always, When::Extended, When::Estimator, When::Medium,
                               When::Resolved};

}  // namespace
}  // namespace settings_table

using Setting = FormFactorSetting;
using When = FormFactorSetting::When;

const std::vector<FormFactorSetting>& form_factor_settings() {
  static const std::vector<FormFactorSetting> rows = settings_table::make_settings();
  return rows;
}

bool setting_applies(const FormFactorSetting& s, const FormFactorOptions& o) {
  switch (s.when) {
    case When::Always:
      return true;
    case When::Extended:
      return o.contents.extended;
    case When::Estimator:
      return std::find(s.estimators.begin(), s.estimators.end(), o.estimator) != s.estimators.end();
    case When::Medium:
      return o.contents.medium_zones > 0;
    case When::Resolved:
      return !o.estimator_requested.empty();
  }
  return false;
}

std::string format_ff_settings(const FormFactorOptions& o) {
  std::string out;
  for (const When group : settings_table::kTextOrder)
    for (const Setting& s : form_factor_settings()) {
      if (s.when != group || *s.key == '\0' || !setting_applies(s, o)) continue;
      if (!out.empty()) out += ' ';
      out += std::string(s.key) + '=' + s.text(o);
    }
  return out;
}

bool parse_ff_settings(const std::string& text, FormFactorOptions& options) {
  const std::vector<Setting>& rows = form_factor_settings();
  const auto row_of = [&](const std::string& key) {
    return std::find_if(rows.begin(), rows.end(),
                        [&](const Setting& s) { return *s.key != '\0' && key == s.key; }) -
           rows.begin();
  };
  FormFactorOptions o = options;
  for (const Setting& s : rows)
    if (s.absent) s.read(s, s.absent, o);
  std::vector<char> given(rows.size(), 0), valid(rows.size(), 0);
  FormFactorOptions ignored;  // what a legacy key that yields reads into
  std::istringstream in(text);
  for (std::string pair; in >> pair;) {
    const size_t eq = pair.find('=');
    if (eq == std::string::npos) continue;
    const size_t r = static_cast<size_t>(row_of(pair.substr(0, eq)));
    if (r == rows.size()) continue;  // another writer's note (patches=, max_edge=)
    const Setting& s = rows[r];
    given[r] = 1;
    const bool yields = s.yields_to && given[static_cast<size_t>(row_of(s.yields_to))];
    const bool ok = s.read(s, pair.substr(eq + 1), yields ? ignored : o);
    if (s.required)
      valid[r] = ok;
    else if (!ok)
      return false;
  }
  for (size_t r = 0; r < rows.size(); ++r)
    if (rows[r].required && !valid[r]) return false;
  options = o;
  return true;
}

Json ff_settings_report(const FormFactorOptions& o) {
  Json out = Json::object();
  for (const Setting& s : form_factor_settings()) {
    if (*s.name == '\0') continue;
    const bool shown = setting_applies(s, o) && (s.when != When::Always || !o.estimator.empty());
    out[s.name] = shown ? s.value(o) : Json();
  }
  return out;
}

}  // namespace lambert
