#pragma once
// Reading the per-patch radiosity CSV written by `lambert solve` (columns patch, surface,
// area, R, G, B; one header line) back onto a meshed scene, e.g. for `lambert render`.

#include <Eigen/Core>
#include <istream>
#include <string>

#include "geometry/mesh/mesh.hpp"

namespace lambert {

/// Relative area mismatch tolerated between the CSV and the mesh: the writer prints areas
/// with >= 10 significant digits, so 1e-6 accepts any rounding and rejects another meshing
/// (whose patch areas differ by O(1) relative).
constexpr double kCsvAreaTolerance = 1e-6;

/// Reads B (N x 3) for `mesh` from `path`. The header names the columns (patch, area, R, G,
/// B are required, in any order; others are ignored); rows may come in any order but every
/// patch 0..N-1 must appear exactly once with its mesh area. Every row has as many cells as
/// the header (RFC 4180 quoting); the patch is a decimal integer, the other values strict
/// finite decimals (io/strict_number), radiosities >= 0; a column name appears once; lines
/// are bounded (io/line_reader); blank lines and lines starting with '#' are skipped.
/// Throws IoError (unreadable) or SceneError with a one-line "FILE:LINE: ..." message on any
/// mismatch or malformed value.
Eigen::MatrixX3d read_radiosity_csv(const std::string& path, const PatchMesh& mesh);

/// read_radiosity_csv from a stream named `name` in messages (tests and fuzzing).
Eigen::MatrixX3d read_radiosity_csv_stream(std::istream& in, const std::string& name,
                                           const PatchMesh& mesh);

}  // namespace lambert
