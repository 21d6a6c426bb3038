#include "io/heat_surfaces.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "io/json.hpp"

namespace lambert {
namespace {

std::string num(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

double number_of(const Json& v, const std::string& where, const char* key) {
  if (!v.is_number()) throw SceneError(where + ": \"" + key + "\" must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw SceneError(where + ": \"" + key + "\" must be finite");
  return x;
}

SurfaceCondition parse_entry(const Json& e, const std::string& where) {
  if (!e.is_object())
    throw SceneError(where +
                     ": expected an object such as {\"emissivity\": 0.8, \"temperature\": 500}");
  SurfaceCondition c;
  bool has_e = false, has_t = false, has_q = false;
  for (const auto& [key, v] : e.items()) {
    if (key == "emissivity") {
      c.emissivity = number_of(v, where, "emissivity");
      has_e = true;
    } else if (key == "temperature") {
      c.value = number_of(v, where, "temperature");
      has_t = true;
    } else if (key == "heat_flux") {
      c.value = number_of(v, where, "heat_flux");
      has_q = true;
    } else {
      throw SceneError(where + ": unknown key \"" + key +
                       "\" (expected emissivity and one of temperature, heat_flux)");
    }
  }
  if (!has_e) throw SceneError(where + ": \"emissivity\" is missing");
  if (has_t == has_q)
    throw SceneError(where + ": give exactly one of \"temperature\" (K) and \"heat_flux\" (W/m^2)");
  c.known_temperature = has_t;
  if (!(c.emissivity >= 0.0 && c.emissivity <= 1.0))
    throw SceneError(where + ": emissivity " + num(c.emissivity) + " must lie in [0, 1]");
  if (has_t && c.value < 0.0)
    throw SceneError(where + ": temperature " + num(c.value) + " K must be >= 0");
  if (has_q && c.emissivity == 0.0)
    throw SceneError(where +
                     ": a surface with a known heat_flux needs emissivity > 0 (a perfect "
                     "reflector exchanges nothing and has no radiative temperature)");
  return c;
}

}  // namespace

SurfaceConditions parse_surface_conditions(const std::string& text, const std::string& name) {
  // A key given twice in one object is an error (nlohmann keeps the last silently): the
  // keys of each open object, innermost last.
  std::vector<std::set<std::string>> open_objects;
  const Json::parser_callback_t no_duplicates = [&](int, Json::parse_event_t event, Json& parsed) {
    if (event == Json::parse_event_t::object_start) open_objects.emplace_back();
    if (event == Json::parse_event_t::object_end && !open_objects.empty()) open_objects.pop_back();
    if (event == Json::parse_event_t::key && !open_objects.empty() &&
        !open_objects.back().insert(parsed.get<std::string>()).second)
      throw SceneError(name + ": key \"" + parsed.get<std::string>() +
                       "\" given twice in one object");
    return true;
  };
  Json j;
  try {
    j = Json::parse(text, no_duplicates);
  } catch (const Json::exception& e) {  // syntax, and numbers out of range such as 1e400
    throw SceneError(name + ": not valid JSON: " + e.what());
  }
  if (!j.is_object() || j.empty())
    throw SceneError(name + ": expected an object mapping surface names (or \"*\") to conditions");
  SurfaceConditions out;
  out.file = name;
  for (const auto& [key, v] : j.items())
    out.by_name[key] = parse_entry(v, name + ": surface \"" + key + "\"");
  return out;
}

SurfaceConditions read_surface_conditions(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(path + ": read error");
  return parse_surface_conditions(text, path);
}

std::vector<SurfaceCondition> resolve_surface_conditions(const SurfaceConditions& conditions,
                                                         const std::vector<std::string>& names) {
  const std::set<std::string> known(names.begin(), names.end());
  for (const auto& [name, c] : conditions.by_name)
    if (name != "*" && !known.count(name))
      throw SceneError(conditions.file + ": surface \"" + name +
                       "\" is not in the scene (lambert info --list-surfaces lists the names)");
  const auto star = conditions.by_name.find("*");
  std::vector<SurfaceCondition> out;
  for (const auto& name : names) {
    const auto it = conditions.by_name.find(name);
    if (it != conditions.by_name.end()) {
      out.push_back(it->second);
    } else if (star != conditions.by_name.end()) {
      out.push_back(star->second);
    } else {
      throw SceneError(conditions.file + ": surface \"" + name +
                       "\" has no condition and there is no \"*\" default");
    }
  }
  return out;
}

}  // namespace lambert
