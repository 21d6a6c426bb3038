#pragma once
// Saved form-factor matrices: Matrix Market (text, for scipy.io.mmread and friends) and a
// compact binary format with a header that ties the file to the meshed scene.

#include <cstdint>
#include <string>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert {

/// Identity of the meshed scene and settings stored with a saved F.
struct FormFactorFileInfo {
  std::uint64_t mesh_hash = 0;  ///< mesh_hash() of the PatchMesh F was computed on
  std::string settings;         ///< human-readable settings (estimator, samples, seed, ...)
};

/// Writes F in Matrix Market coordinate real general format (1-based), atomically. The
/// header comments carry the mesh hash and the settings.
void write_matrix_market(const std::string& path, const SparseF& F, const FormFactorFileInfo& info);

/// Writes F (and its standard errors when present) in lambert's binary format, atomically.
void write_ff_binary(const std::string& path, const FormFactors& ff, const FormFactorFileInfo& info);

/// Reads a saved F (binary or Matrix Market, by content) and checks that it was made from
/// the same meshed scene: throws SceneError naming the file if the hash or size differ,
/// IoError if unreadable or corrupt.
FormFactors read_form_factors(const std::string& path, std::uint64_t expected_mesh_hash,
                              std::int32_t expected_n, FormFactorFileInfo* info = nullptr);

}  // namespace lambert
