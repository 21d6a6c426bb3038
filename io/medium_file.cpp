#include "io/medium_file.hpp"

#include <cmath>
#include <fstream>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/strict_number.hpp"

namespace lambert {
namespace {

// Parses tokens [1, count] of a line as finite numbers.
std::vector<double> numbers(const std::vector<std::string_view>& tokens, size_t first, size_t count,
                            const LineReader& reader) {
  if (tokens.size() != first + count)
    throw SceneError(reader.where() + ": expected " + std::to_string(count) + " numbers, found " +
                     std::to_string(tokens.size() - first));
  std::vector<double> out(count);
  for (size_t k = 0; k < count; ++k) {
    const std::string why = parse_finite(tokens[first + k], out[k]);
    if (!why.empty())
      throw SceneError(reader.where() + ": '" + std::string(tokens[first + k]) + "': " + why);
  }
  return out;
}

}  // namespace

Medium read_medium_grid(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open the medium grid file");
  return read_medium_grid_stream(in, path);
}

Medium read_medium_grid_stream(std::istream& in, const std::string& path) {
  LineReader reader(in, path);
  Medium m;
  m.source = path;
  bool have_bounds = false, have_resolution = false;
  std::int64_t voxel = 0, count = 0;
  std::string_view line;
  std::vector<std::string_view> tokens;
  while (reader.next(line)) {
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    if ((tokens[0] == "bounds" && have_bounds) || (tokens[0] == "resolution" && have_resolution))
      throw SceneError(reader.where() + ": repeated '" + std::string(tokens[0]) + "'");
    if (tokens[0] == "bounds") {
      const std::vector<double> b = numbers(tokens, 1, 6, reader);
      m.lo = {b[0], b[1], b[2]};
      m.hi = {b[3], b[4], b[5]};
      if (!((m.hi - m.lo).minCoeff() > 0.0))
        throw SceneError(reader.where() +
                         ": empty or inverted bounds (need X0 < X1, Y0 < Y1, Z0 < Z1)");
      have_bounds = true;
    } else if (tokens[0] == "resolution") {
      const std::vector<double> r = numbers(tokens, 1, 3, reader);
      for (int a = 0; a < 3; ++a) {
        if (r[a] < 1 || r[a] > 1e6 || r[a] != std::floor(r[a]))
          throw SceneError(reader.where() + ": the resolution must be three integers >= 1");
        m.resolution[a] = static_cast<int>(r[a]);
      }
      count = std::int64_t{m.resolution.x()} * m.resolution.y() * m.resolution.z();
      if (count > kMaxMediumVoxels)
        throw SceneError(reader.where() + ": more than " + std::to_string(kMaxMediumVoxels) +
                         " voxels");
      m.sigma_a.resize(count, 3);
      m.sigma_s.resize(count, 3);
      m.emission.resize(count, 3);
      have_resolution = true;
    } else {
      if (!have_bounds || !have_resolution)
        throw SceneError(reader.where() +
                         ": 'bounds' and 'resolution' must come before the voxels");
      if (voxel >= count)
        throw SceneError(reader.where() + ": more voxel lines than the resolution's " +
                         std::to_string(count));
      const std::vector<double> v = numbers(tokens, 0, 9, reader);
      for (int c = 0; c < 3; ++c) {
        m.sigma_a(voxel, c) = v[c];
        m.sigma_s(voxel, c) = v[3 + c];
        m.emission(voxel, c) = v[6 + c];
      }
      for (double x : v)
        if (x < 0.0) throw SceneError(reader.where() + ": coefficients must be >= 0");
      const double t0 = v[0] + v[3];
      for (int c = 1; c < 3; ++c)
        if (std::abs(v[c] + v[3 + c] - t0) > 1e-12 * t0)
          throw SceneError(
              reader.where() +
              ": sigma_a + sigma_s must be the same in every channel (grey extinction)");
      if (t0 == 0.0 && (v[6] > 0 || v[7] > 0 || v[8] > 0))
        throw SceneError(reader.where() + ": a voxel that emits needs sigma_a + sigma_s > 0");
      ++voxel;
    }
  }
  if (!have_bounds || !have_resolution)
    throw SceneError(path + ": missing 'bounds' or 'resolution'");
  if (voxel != count)
    throw SceneError(path + ": " + std::to_string(voxel) + " voxel lines, the resolution needs " +
                     std::to_string(count));
  return m;
}

}  // namespace lambert
