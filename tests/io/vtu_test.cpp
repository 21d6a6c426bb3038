// The VTU writer (io/vtu.hpp), read back with an XML parser (expat) and checked strictly:
// the element tree, the attributes VTK's reader needs, and every DataArray decoded bit for bit.
#include "io/vtu.hpp"

#include <expat.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "io/base64.hpp"

namespace lambert {
namespace {

// An element of the parsed file: name, attributes, text and children.
struct Node {
  std::string name, text;
  std::map<std::string, std::string> attrs;
  std::vector<std::unique_ptr<Node>> children;
  // The children named `n`, in order.
  std::vector<const Node*> all(const std::string& n) const {
    std::vector<const Node*> out;
    for (const auto& c : children)
      if (c->name == n) out.push_back(c.get());
    return out;
  }
  // The one child named `n` (fails the test when there is not exactly one).
  const Node& one(const std::string& n) const {
    const auto v = all(n);
    EXPECT_EQ(v.size(), 1u) << "children <" << n << "> of <" << name << ">";
    static const Node kNone;
    return v.empty() ? kNone : *v[0];
  }
};

// Parses an XML text with expat into a tree; fails the test on a parse error.
std::unique_ptr<Node> parse_xml(const std::string& text) {
  struct State {
    std::unique_ptr<Node> root;
    std::vector<Node*> stack;
  } st;
  XML_Parser p = XML_ParserCreate("UTF-8");
  XML_SetUserData(p, &st);
  XML_SetElementHandler(
      p,
      [](void* data, const XML_Char* name, const XML_Char** attrs) {
        auto& s = *static_cast<State*>(data);
        auto node = std::make_unique<Node>();
        node->name = name;
        for (int k = 0; attrs[k] != nullptr; k += 2) node->attrs[attrs[k]] = attrs[k + 1];
        Node* raw = node.get();
        if (s.stack.empty())
          s.root = std::move(node);
        else
          s.stack.back()->children.push_back(std::move(node));
        s.stack.push_back(raw);
      },
      [](void* data, const XML_Char*) { static_cast<State*>(data)->stack.pop_back(); });
  XML_SetCharacterDataHandler(p, [](void* data, const XML_Char* text_part, int len) {
    auto& state = *static_cast<State*>(data);
    if (!state.stack.empty()) state.stack.back()->text.append(text_part, len);
  });
  const bool ok = XML_Parse(p, text.data(), static_cast<int>(text.size()), 1) != XML_STATUS_ERROR;
  EXPECT_TRUE(ok) << "XML error: " << XML_ErrorString(XML_GetErrorCode(p)) << " at line "
                  << XML_GetCurrentLineNumber(p);
  XML_ParserFree(p);
  return std::move(st.root);
}

// A binary DataArray's values: the base64 text is a UInt64 byte count and the values.
template <typename T>
std::vector<T> decode(const Node& array, const std::string& type) {
  EXPECT_EQ(array.name, "DataArray");
  EXPECT_EQ(array.attrs.at("type"), type) << array.attrs.at("Name");
  EXPECT_EQ(array.attrs.at("format"), "binary");
  const std::string raw = base64_decode(array.text);
  std::uint64_t bytes = 0;
  EXPECT_GE(raw.size(), sizeof bytes);
  std::memcpy(&bytes, raw.data(), sizeof bytes);
  EXPECT_EQ(bytes, raw.size() - sizeof bytes) << "byte count of " << array.attrs.at("Name");
  EXPECT_EQ(bytes % sizeof(T), 0u);
  std::vector<T> out((raw.size() - sizeof bytes) / sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), raw.data() + sizeof bytes, out.size() * sizeof(T));
  return out;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Two surfaces: a unit quad in z = 0 (surface 0) and two triangles above it (surface 1).
PatchMesh small_mesh() {
  PatchMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0.25, 1e-300, 1}};
  m.vertex_surface = {0, 0, 0, 0, 1, 1, 1, 1};
  Patch quad;
  quad.vertices = {0, 1, 2, 3};
  quad.vertex_count = 4;
  Patch t1, t2;
  t1.vertices = {4, 5, 6, 0};
  t2.vertices = {4, 6, 7, 0};
  t1.surface = t2.surface = 1;
  m.patches = {quad, t1, t2};
  m.surface_names = {"floor", "lid & <top>"};
  return m;
}

TEST(Vtu, StructureCountsOffsetsAndTypesReadBackExactly) {
  testing::TempDir dir;
  const PatchMesh mesh = small_mesh();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  VtuContent c;
  c.cell_data = {{"T_K", std::vector<double>{300.5, nan, 1.0 / 3.0}},
                 {"surface", std::vector<std::int32_t>{0, 1, 1}}};
  c.field_data = {vtu_string_array("surface_names", mesh.surface_names),
                  {"surface_Q_W", std::vector<double>{-2.5, 2.5}}};
  c.comments = {"a comment with -- inside", "surface 1: lid & <top>"};
  const std::string path = dir.file("m.vtu");
  write_vtu(path, mesh, c);
  const std::unique_ptr<Node> root = parse_xml(slurp(path));
  ASSERT_TRUE(root);

  EXPECT_EQ(root->name, "VTKFile");
  EXPECT_EQ(root->attrs.at("type"), "UnstructuredGrid");
  EXPECT_EQ(root->attrs.at("version"), "1.0");
  EXPECT_EQ(root->attrs.at("header_type"), "UInt64");
  EXPECT_EQ(root->attrs.at("byte_order"), "LittleEndian");  // x86-64 and arm64 hosts
  ASSERT_EQ(root->children.size(), 1u);
  const Node& grid = root->one("UnstructuredGrid");
  ASSERT_EQ(grid.children.size(), 2u);  // FieldData, Piece

  const auto fields = grid.one("FieldData").all("DataArray");
  ASSERT_EQ(fields.size(), 2u);
  EXPECT_EQ(fields[0]->attrs.at("Name"), "surface_names");
  const auto names = decode<std::uint8_t>(*fields[0], "UInt8");
  const std::string expected_names("floor\0lid & <top>\0", 18);
  EXPECT_EQ(std::string(names.begin(), names.end()), expected_names);
  EXPECT_EQ(fields[0]->attrs.at("NumberOfTuples"), "18");
  EXPECT_EQ(decode<double>(*fields[1], "Float64"), (std::vector<double>{-2.5, 2.5}));
  EXPECT_EQ(fields[1]->attrs.at("NumberOfTuples"), "2");

  const Node& piece = grid.one("Piece");
  EXPECT_EQ(piece.attrs.at("NumberOfPoints"), "8");
  EXPECT_EQ(piece.attrs.at("NumberOfCells"), "3");
  ASSERT_EQ(piece.children.size(), 3u);  // Points, Cells, CellData
  const Node& pts = piece.one("Points").one("DataArray");
  EXPECT_EQ(pts.attrs.at("NumberOfComponents"), "3");
  const auto xyz = decode<double>(pts, "Float64");
  ASSERT_EQ(xyz.size(), 3 * mesh.vertices.size());
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(xyz[3 * v + k], mesh.vertices[v][k]);  // bit for bit

  const Node& cells = piece.one("Cells");
  ASSERT_EQ(cells.children.size(), 3u);
  const auto by_name = [](const Node& parent, const std::string& n) -> const Node& {
    for (const Node* a : parent.all("DataArray"))
      if (a->attrs.at("Name") == n) return *a;
    ADD_FAILURE() << "no DataArray " << n;
    static const Node kNone;
    return kNone;
  };
  EXPECT_EQ(decode<std::int64_t>(by_name(cells, "connectivity"), "Int64"),
            (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5, 6, 4, 6, 7}));
  EXPECT_EQ(decode<std::int64_t>(by_name(cells, "offsets"), "Int64"),
            (std::vector<std::int64_t>{4, 7, 10}));
  EXPECT_EQ(decode<std::uint8_t>(by_name(cells, "types"), "UInt8"),
            (std::vector<std::uint8_t>{9, 5, 5}));  // VTK_QUAD, VTK_TRIANGLE

  const Node& cd = piece.one("CellData");
  ASSERT_EQ(cd.children.size(), 2u);
  const auto t = decode<double>(by_name(cd, "T_K"), "Float64");
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0], 300.5);
  EXPECT_TRUE(std::isnan(t[1]));
  EXPECT_EQ(t[2], 1.0 / 3.0);
  EXPECT_EQ(decode<std::int32_t>(by_name(cd, "surface"), "Int32"),
            (std::vector<std::int32_t>{0, 1, 1}));
}

TEST(Vtu, ACellArrayOfTheWrongLengthIsAnInternalError) {
  testing::TempDir dir;
  VtuContent c;
  c.cell_data = {{"T_K", std::vector<double>{1.0, 2.0}}};
  EXPECT_THROW(write_vtu(dir.file("m.vtu"), small_mesh(), c), InternalError);
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.vtu")));
}

TEST(Vtu, AnEmptyMeshIsAValidFileWithZeroCells) {
  testing::TempDir dir;
  write_vtu(dir.file("e.vtu"), PatchMesh{}, {});
  const std::unique_ptr<Node> root = parse_xml(slurp(dir.file("e.vtu")));
  ASSERT_TRUE(root);
  const Node& piece = root->one("UnstructuredGrid").one("Piece");
  EXPECT_EQ(piece.attrs.at("NumberOfCells"), "0");
  const auto cell_arrays = piece.one("Cells").all("DataArray");
  ASSERT_EQ(cell_arrays.size(), 3u);
  EXPECT_TRUE(decode<std::int64_t>(*cell_arrays[0], "Int64").empty());
}

TEST(Base64, Rfc4648VectorsRoundTrip) {
  const std::vector<std::pair<std::string, std::string>> cases = {{"", ""},
                                                                  {"f", "Zg=="},
                                                                  {"fo", "Zm8="},
                                                                  {"foo", "Zm9v"},
                                                                  {"foob", "Zm9vYg=="},
                                                                  {"fooba", "Zm9vYmE="},
                                                                  {"foobar", "Zm9vYmFy"}};
  for (const auto& [plain, coded] : cases) {
    EXPECT_EQ(base64_encode(plain), coded);
    EXPECT_EQ(base64_decode(coded), plain);
  }
  std::string bytes;
  for (int b = 0; b < 256; ++b) bytes.push_back(static_cast<char>(b));
  EXPECT_EQ(base64_decode(base64_encode(bytes)), bytes);
}

TEST(Base64, MalformedTextIsRefused) {
  EXPECT_THROW(base64_decode("Zg="), IoError);     // length not a multiple of 4
  EXPECT_THROW(base64_decode("Z=g="), IoError);    // padding inside
  EXPECT_THROW(base64_decode("Zm9v\n"), IoError);  // a character outside the alphabet
}

}  // namespace
}  // namespace lambert
