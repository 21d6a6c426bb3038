#include "io/radiosity_csv.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <vector>

#include "core/error.hpp"

namespace lambert {
namespace {

// Splits one CSV record (RFC 4180: "..." quoting with "" for a quote) and trims blanks.
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  bool quoted = false;
  for (size_t k = 0; k < line.size(); ++k) {
    const char c = line[k];
    if (quoted) {
      if (c == '"' && k + 1 < line.size() && line[k + 1] == '"') {
        cell.push_back('"');
        ++k;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell.push_back(c);
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cell);
      cell.clear();
    } else if (c != '\r') {
      cell.push_back(c);
    }
  }
  out.push_back(cell);
  for (auto& s : out) {
    const auto b = s.find_first_not_of(" \t");
    const auto e = s.find_last_not_of(" \t");
    s = b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  }
  return out;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

Eigen::MatrixX3d read_radiosity_csv(const std::string& path, const PatchMesh& mesh) {
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& msg) -> SceneError {
    return SceneError(path + ":" + std::to_string(line_no) + ": " + msg);
  };
  // Header: find the required columns by name.
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    header = split_csv(line);
    break;
  }
  if (header.empty()) throw SceneError(path + ": empty radiosity CSV");
  const char* required[] = {"patch", "area", "r", "g", "b"};
  int col[5];
  for (int k = 0; k < 5; ++k) {
    std::vector<std::string> names;
    for (const auto& h : header) names.push_back(lower(h));
    const auto it = std::find(names.begin(), names.end(), required[k]);
    if (it == names.end())
      throw fail(std::string("header has no '") + required[k] +
                 "' column (expected patch,surface,area,R,G,B as written by `lambert solve`)");
    col[k] = static_cast<int>(it - names.begin());
  }
  // Parse every row first, so a file for another meshing is reported by its patch count.
  struct Row {
    int line = 0;
    double v[5];
    std::string area_text;
  };
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    const auto cells = split_csv(line);
    Row row;
    row.line = line_no;
    for (int k = 0; k < 5; ++k) {
      if (col[k] >= static_cast<int>(cells.size()))
        throw fail("expected " + std::to_string(header.size()) + " columns, found " +
                   std::to_string(cells.size()));
      const std::string& s = cells[col[k]];
      char* end = nullptr;
      row.v[k] = std::strtod(s.c_str(), &end);
      if (s.empty() || *end != '\0' || !std::isfinite(row.v[k]))
        throw fail("'" + s + "' is not a number (column " + header[col[k]] + ")");
    }
    row.area_text = cells[col[1]];
    rows.push_back(row);
  }
  const std::int32_t n = mesh.size();
  if (static_cast<std::int64_t>(rows.size()) != n)
    throw SceneError(path + ": " + std::to_string(rows.size()) +
                     " patches but the meshed scene has " + std::to_string(n) +
                     " (mesh with the same scene and --patches/--max-edge as the solve)");
  Eigen::MatrixX3d B = Eigen::MatrixX3d::Zero(n, 3);
  std::vector<int> seen_on(n, 0);
  for (const Row& row : rows) {
    line_no = row.line;
    const double* v = row.v;
    if (v[0] != std::floor(v[0]) || v[0] < 0 || v[0] >= n)
      throw fail("patch " + std::to_string(v[0]) + " does not exist: the meshed scene has " +
                 std::to_string(n) + " patches");
    const auto i = static_cast<std::int32_t>(v[0]);
    if (seen_on[i])
      throw fail("patch " + std::to_string(i) + " repeated (first on line " +
                 std::to_string(seen_on[i]) + ")");
    seen_on[i] = row.line;
    const double a = mesh.patches[i].area;
    if (std::abs(v[1] - a) > kCsvAreaTolerance * a) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.10g", a);
      throw fail("patch " + std::to_string(i) + " has area " + row.area_text +
                 " but the meshed scene's is " + buf + " (written for another scene or meshing?)");
    }
    if (v[2] < 0 || v[3] < 0 || v[4] < 0) throw fail("negative radiosity");
    B.row(i) << v[2], v[3], v[4];
  }
  return B;
}

}  // namespace lambert
