#pragma once
// VTK XML UnstructuredGrid (.vtu) output of the patch mesh with per-patch values, for
// ParaView, VisIt and meshio: the patches as cells (triangles VTK type 5, quads type 9,
// wound like the patch: front = CCW), the values as CellData, a table (one row per surface)
// as FieldData.
//
// Layout (VTK's "XML File Formats", version 1.0, header_type UInt64): one Piece; Points
// Float64 × 3 in the scene's coordinates (every PatchMesh vertex); Cells: connectivity and
// offsets Int64, types UInt8. Every DataArray is format="binary": base64 of a UInt64 byte
// count followed by the raw values in the machine's byte order (stated in byte_order). Binary
// rather than ASCII so that doubles come back bit for bit and NaN (an undefined value, e.g. a
// temperature heat cannot define) is NaN in every reader: VTK parses ASCII with iostreams,
// which refuse "nan". FieldData arrays carry NumberOfTuples (VTK requires it there).
//
// Strings: VTK's String type is read by VTK but refused by meshio (its reader knows numeric
// types only), so a list of names is a UInt8 array of the names' UTF-8 bytes, each followed by
// a 0 byte — the byte sequence VTK's own String array has in ASCII files — and the names are
// also listed in XML comments at the top of the file.

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "geometry/mesh/mesh.hpp"

namespace lambert {

/// One named DataArray with one component: Float64, Int32 or UInt8 values.
struct VtuArray {
  std::string name;
  std::variant<std::vector<double>, std::vector<std::int32_t>, std::vector<std::uint8_t>> values;
  /// Number of values (tuples).
  std::size_t size() const;
};

/// A UInt8 array holding `names` as UTF-8, each followed by a 0 byte (see the header comment).
VtuArray vtu_string_array(const std::string& name, const std::vector<std::string>& names);

/// What a VTU carries besides the mesh.
struct VtuContent {
  std::vector<VtuArray> cell_data;    ///< each with one value per patch, in patch order
  std::vector<VtuArray> field_data;   ///< any length (e.g. one value per surface)
  std::vector<std::string> comments;  ///< XML comment lines after the declaration ("--" is
                                      ///< written as "- -": XML forbids it in a comment)
};

/// Writes `mesh` with `content` as a VTK XML UnstructuredGrid, atomically. A cell array whose
/// length is not mesh.size() is a LAMBERT_CHECK. Throws IoError.
void write_vtu(const std::string& path, const PatchMesh& mesh, const VtuContent& content);

}  // namespace lambert
