#include "io/radiosity_csv.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <vector>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/strict_number.hpp"

namespace lambert {
namespace {

// Splits one CSV record (RFC 4180: "..." quoting with "" for a quote) and trims blanks.
// Returns a reason for an unterminated quote or text after a closing quote, else "".
std::string split_csv(std::string_view line, std::vector<std::string>& out) {
  out.clear();
  std::string cell;
  bool quoted = false, closed = false;
  for (size_t k = 0; k < line.size(); ++k) {
    const char c = line[k];
    if (quoted) {
      if (c == '"' && k + 1 < line.size() && line[k + 1] == '"') {
        cell.push_back('"');
        ++k;
      } else if (c == '"') {
        quoted = false;
        closed = true;
      } else {
        cell.push_back(c);
      }
    } else if (c == ',') {
      out.push_back(cell);
      cell.clear();
      closed = false;
    } else if (c == '"' && cell.find_first_not_of(" \t") == std::string::npos) {
      quoted = true;
    } else if (closed && !is_blank(c)) {
      return "text after a closing quote";
    } else {
      cell.push_back(c);
    }
  }
  if (quoted) return "unterminated quote";
  out.push_back(cell);
  for (auto& s : out) {
    const auto first = s.find_first_not_of(" \t");
    const auto last = s.find_last_not_of(" \t");
    s = first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
  }
  return "";
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool skipped(std::string_view line) {
  const auto k = line.find_first_not_of(" \t");
  return k == std::string_view::npos || line[k] == '#';
}

// The header: every name once (case-insensitive); the columns of patch, area, R, G, B.
std::array<size_t, 5> header_columns(const std::vector<std::string>& header,
                                     const std::string& where) {
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (const auto& h : header) {
    names.push_back(lower(h));
    if (!seen.insert(names.back()).second)
      throw SceneError(where + ": column '" + h + "' appears twice in the header");
  }
  const char* required[] = {"patch", "area", "r", "g", "b"};
  std::array<size_t, 5> col{};
  for (int k = 0; k < 5; ++k) {
    const auto it = std::find(names.begin(), names.end(), required[k]);
    if (it == names.end())
      throw SceneError(where + ": header has no '" + required[k] +
                       "' column (expected patch,surface,area,R,G,B as written by `lambert solve`)");
    col[k] = static_cast<size_t>(it - names.begin());
  }
  return col;
}

struct Row {
  int line = 0;
  std::int64_t patch = 0;
  double v[4];  // area, R, G, B
  std::string area_text;
};

// One data row: as many cells as the header, an integer patch, finite numbers.
Row parse_row(const std::vector<std::string>& cells, const std::vector<std::string>& header,
              const std::array<size_t, 5>& col, const std::string& where) {
  if (cells.size() != header.size())
    throw SceneError(where + ": expected " + std::to_string(header.size()) + " columns, found " +
                     std::to_string(cells.size()));
  Row row;
  std::string why = parse_integer(cells[col[0]], row.patch);
  if (!why.empty())
    throw SceneError(where + ": patch '" + cells[col[0]] + "' is not a patch index (" + why + ")");
  for (int k = 0; k < 4; ++k) {
    why = parse_finite(cells[col[k + 1]], row.v[k]);
    if (!why.empty())
      throw SceneError(where + ": '" + cells[col[k + 1]] + "' (column " + header[col[k + 1]] +
                       "): " + why);
  }
  row.area_text = cells[col[1]];
  return row;
}

}  // namespace

Eigen::MatrixX3d read_radiosity_csv_stream(std::istream& in, const std::string& name,
                                           const PatchMesh& mesh) {
  LineReader lines(in, name);
  std::string_view line;
  std::vector<std::string> header, cells;
  auto split = [&](std::vector<std::string>& out) {
    const std::string why = split_csv(line, out);
    if (!why.empty()) throw SceneError(lines.where() + ": " + why);
  };
  while (header.empty() && lines.next(line))
    if (!skipped(line)) split(header);
  if (header.empty()) throw SceneError(name + ": empty radiosity CSV");
  const std::array<size_t, 5> col = header_columns(header, lines.where());
  // Parse every row first, so a file for another meshing is reported by its patch count.
  std::vector<Row> rows;
  while (lines.next(line)) {
    if (skipped(line)) continue;
    split(cells);
    rows.push_back(parse_row(cells, header, col, lines.where()));
    rows.back().line = lines.line_number();
  }
  const std::int32_t n = mesh.size();
  if (static_cast<std::int64_t>(rows.size()) != n)
    throw SceneError(name + ": " + std::to_string(rows.size()) +
                     " patches but the meshed scene has " + std::to_string(n) +
                     " (mesh with the same scene and --patches/--max-edge as the solve)");
  Eigen::MatrixX3d B = Eigen::MatrixX3d::Zero(n, 3);
  std::vector<int> seen_on(n, 0);
  for (const Row& row : rows) {
    const std::string where = name + ":" + std::to_string(row.line);
    if (row.patch < 0 || row.patch >= n)
      throw SceneError(where + ": patch " + std::to_string(row.patch) +
                       " does not exist: the meshed scene has " + std::to_string(n) + " patches");
    const auto i = static_cast<std::int32_t>(row.patch);
    if (seen_on[i])
      throw SceneError(where + ": patch " + std::to_string(i) + " repeated (first on line " +
                       std::to_string(seen_on[i]) + ")");
    seen_on[i] = row.line;
    const double a = mesh.patches[i].area;
    if (!(std::abs(row.v[0] - a) <= kCsvAreaTolerance * a)) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.10g", a);
      throw SceneError(where + ": patch " + std::to_string(i) + " has area " + row.area_text +
                       " but the meshed scene's is " + buf +
                       " (written for another scene or meshing?)");
    }
    if (row.v[1] < 0 || row.v[2] < 0 || row.v[3] < 0)
      throw SceneError(where + ": negative radiosity");
    B.row(i) << row.v[1], row.v[2], row.v[3];
  }
  return B;
}

Eigen::MatrixX3d read_radiosity_csv(const std::string& path, const PatchMesh& mesh) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  return read_radiosity_csv_stream(in, path, mesh);
}

}  // namespace lambert
