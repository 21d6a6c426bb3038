#include "io/camera_file.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <vector>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/strict_number.hpp"

namespace lambert {
namespace {

// Number of values each key takes.
const std::map<std::string, size_t, std::less<>> kKeyArity = {
    {"eye", 3}, {"look_at", 3}, {"up", 3}, {"vfov", 1}, {"focal_mm", 1}, {"film_mm", 1}};

struct SidecarValues {
  std::map<std::string, std::vector<double>, std::less<>> values;
  std::map<std::string, int, std::less<>> line_of;  // where each key was given
};

// Parses every line into key -> values, refusing unknown and repeated keys and wrong counts.
SidecarValues read_values(std::istream& in, const std::string& name) {
  LineReader lines(in, name);
  SidecarValues out;
  std::vector<std::string_view> tok;
  for (std::string_view line; lines.next(line);) {
    split_tokens(line, tok);
    if (tok.empty()) continue;
    const std::string key(tok[0]);
    const auto arity = kKeyArity.find(key);
    if (arity == kKeyArity.end())
      throw SceneError(lines.where() + ": unknown camera key '" + key +
                       "' (expected eye, look_at, up, vfov, focal_mm, film_mm)");
    if (const auto first = out.line_of.find(key); first != out.line_of.end())
      throw SceneError(lines.where() + ": '" + key + "' repeated (first on line " +
                       std::to_string(first->second) + ")");
    if (tok.size() - 1 != arity->second)
      throw SceneError(lines.where() + ": '" + key + "' needs " + std::to_string(arity->second) +
                       " number(s), found " + std::to_string(tok.size() - 1) + " field(s)");
    std::vector<double>& v = out.values[key];
    v.resize(arity->second);
    for (size_t k = 0; k < v.size(); ++k) {
      const std::string why = parse_finite(tok[k + 1], v[k]);
      if (!why.empty())
        throw SceneError(lines.where() + ": '" + key + "': '" + std::string(tok[k + 1]) +
                         "' " + why);
    }
    out.line_of[key] = lines.line_number();
  }
  return out;
}

}  // namespace

Camera read_camera_stream(std::istream& in, const std::string& name) {
  const SidecarValues s = read_values(in, name);
  const auto at = [&](const char* key) { return name + ":" + std::to_string(s.line_of.at(key)); };
  const auto vec = [&](const char* key) {
    const auto& v = s.values.at(key);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  };
  for (const char* key : {"eye", "look_at"})
    if (!s.values.count(key)) throw SceneError(name + ": camera needs 'eye' and 'look_at'");
  const bool focal = s.values.count("focal_mm"), film = s.values.count("film_mm");
  if (focal != film)
    throw SceneError(at(focal ? "focal_mm" : "film_mm") + ": '" +
                     (focal ? "focal_mm" : "film_mm") + "' needs '" + (focal ? "film_mm" : "focal_mm") +
                     "' too (the field of view is their ratio)");
  if (focal && s.values.count("vfov"))
    throw SceneError(at("vfov") + ": 'vfov' and 'focal_mm'/'film_mm' both set the field of view");
  Camera cam;
  cam.eye = vec("eye");
  cam.look_at = vec("look_at");
  if (s.values.count("up")) cam.up = vec("up");
  const char* fov_key = focal ? "focal_mm" : "vfov";
  if (focal) {
    const double f = s.values.at("focal_mm")[0], w = s.values.at("film_mm")[0];
    if (!(f > 0) || !(w > 0))
      throw SceneError(at(!(f > 0) ? "focal_mm" : "film_mm") + ": focal length and film width must be positive");
    cam.vfov_degrees = 2.0 * std::atan(0.5 * w / f) * 180.0 / M_PI;
  } else if (s.values.count("vfov")) {
    cam.vfov_degrees = s.values.at("vfov")[0];
  }
  if (s.values.count(fov_key) && !(cam.vfov_degrees > 0 && cam.vfov_degrees < 180))
    throw SceneError(at(fov_key) + ": field of view " + std::to_string(cam.vfov_degrees) +
                     " degrees is outside (0, 180) (a pinhole cannot see more)");
  const std::string problem = camera_problem(cam);
  if (!problem.empty())
    throw SceneError(at(problem.find("up") == 0 && s.values.count("up") ? "up" : "look_at") +
                     ": " + problem);
  cam.defined = true;
  return cam;
}

Camera read_camera_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  return read_camera_stream(in, path);
}

}  // namespace lambert
