#include "io/vtu.hpp"

#include <cstring>
#include <ostream>
#include <string_view>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/base64.hpp"
#include "io/xml_escape.hpp"

namespace lambert {
namespace {

// VTK cell types (vtkCellType.h).
constexpr std::uint8_t kVtkTriangle = 5;
constexpr std::uint8_t kVtkQuad = 9;

bool little_endian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

template <typename T>
const char* vtk_type();
template <>
const char* vtk_type<double>() {
  return "Float64";
}
template <>
const char* vtk_type<std::int32_t>() {
  return "Int32";
}
template <>
const char* vtk_type<std::int64_t>() {
  return "Int64";
}
template <>
const char* vtk_type<std::uint8_t>() {
  return "UInt8";
}

// A comment's text with every "--" broken up (XML 1.0, section 2.5) and no trailing '-'.
std::string comment_text(std::string text) {
  for (std::size_t k = text.find("--"); k != std::string::npos; k = text.find("--", k))
    text.insert(k + 1, " ");
  if (!text.empty() && text.back() == '-') text.push_back(' ');
  return text;
}

// One binary DataArray element: base64 of (UInt64 byte count, the values), on one line.
// `extra` holds further attributes (NumberOfComponents, NumberOfTuples).
template <typename T>
void write_array(std::ostream& out, const std::string& indent, const std::string& name,
                 const std::vector<T>& values, const std::string& extra = "") {
  const std::uint64_t bytes = values.size() * sizeof(T);
  std::string raw(sizeof bytes + bytes, '\0');
  std::memcpy(raw.data(), &bytes, sizeof bytes);
  if (bytes > 0) std::memcpy(raw.data() + sizeof bytes, values.data(), bytes);
  out << indent << "<DataArray type=\"" << vtk_type<T>() << "\" Name=\"" << xml_escape(name) << '"'
      << extra << " format=\"binary\">" << base64_encode(raw) << "</DataArray>\n";
}

void write_array(std::ostream& out, const std::string& indent, const VtuArray& a,
                 const std::string& extra = "") {
  std::visit([&](const auto& values) { write_array(out, indent, a.name, values, extra); },
             a.values);
}

}  // namespace

std::size_t VtuArray::size() const {
  return std::visit([](const auto& v) { return v.size(); }, values);
}

VtuArray vtu_string_array(const std::string& name, const std::vector<std::string>& names) {
  std::vector<std::uint8_t> bytes;
  for (const auto& n : names) {
    bytes.insert(bytes.end(), n.begin(), n.end());
    bytes.push_back(0);
  }
  return {name, std::move(bytes)};
}

void write_vtu(const std::string& path, const PatchMesh& mesh, const VtuContent& content) {
  for (const VtuArray& a : content.cell_data)
    LAMBERT_CHECK(a.size() == mesh.patches.size(), "vtu: cell array " + a.name + " has " +
                                                       std::to_string(a.size()) + " values for " +
                                                       std::to_string(mesh.size()) + " patches");
  std::vector<double> points;
  points.reserve(3 * mesh.vertices.size());
  for (const auto& v : mesh.vertices) points.insert(points.end(), {v.x(), v.y(), v.z()});
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types;
  for (const Patch& p : mesh.patches) {
    LAMBERT_CHECK(p.vertex_count == 3 || p.vertex_count == 4, "vtu: a patch is no tri or quad");
    for (int k = 0; k < p.vertex_count; ++k) connectivity.push_back(p.vertices[k]);
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    types.push_back(p.vertex_count == 3 ? kVtkTriangle : kVtkQuad);
  }
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "<?xml version=\"1.0\"?>\n";
    out << "<!-- written by lambert " << LAMBERT_VERSION << " -->\n";
    for (const auto& c : content.comments) out << "<!-- " << comment_text(c) << " -->\n";
    out << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\""
        << (little_endian() ? "LittleEndian" : "BigEndian") << "\" header_type=\"UInt64\">\n";
    out << "  <UnstructuredGrid>\n";
    if (!content.field_data.empty()) {
      out << "    <FieldData>\n";
      for (const VtuArray& a : content.field_data)
        write_array(out, "      ", a, " NumberOfTuples=\"" + std::to_string(a.size()) + '"');
      out << "    </FieldData>\n";
    }
    out << "    <Piece NumberOfPoints=\"" << mesh.vertices.size() << "\" NumberOfCells=\""
        << mesh.patches.size() << "\">\n";
    out << "      <Points>\n";
    write_array(out, "        ", "Points", points, " NumberOfComponents=\"3\"");
    out << "      </Points>\n      <Cells>\n";
    write_array(out, "        ", "connectivity", connectivity);
    write_array(out, "        ", "offsets", offsets);
    write_array(out, "        ", "types", types);
    out << "      </Cells>\n";
    if (!content.cell_data.empty()) {
      out << "      <CellData>\n";
      for (const VtuArray& a : content.cell_data) write_array(out, "        ", a);
      out << "      </CellData>\n";
    }
    out << "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  });
}

}  // namespace lambert
