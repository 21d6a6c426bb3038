#pragma once
// Saved form-factor matrices: Matrix Market (text, for scipy.io.mmread and friends) and a
// compact binary format with a header that ties the file to the meshed scene.

#include <cstdint>
#include <istream>
#include <string>

#include "geometry/formfactors/formfactors.hpp"
#include "io/ff_settings.hpp"

namespace lambert {

/// Identity of the meshed scene and settings stored with a saved F.
struct FormFactorFileInfo {
  std::uint64_t mesh_hash = 0;  ///< mesh_hash() of the PatchMesh F was computed on
  std::string settings;         ///< settings text: format_ff_settings() plus mesh notes
};

/// How saved values are stored: Double (exact), or Float (--ff-precision float: half the
/// value bytes; each value and error rounded to the nearest float, a relative error of at
/// most 2^-24 = 6e-8, far below the statistical error of any estimate, and row sums by at
/// most 6e-8 of themselves). Reading always gives doubles.
enum class ValuePrecision { Double, Float };

/// Writes F in Matrix Market coordinate real general format (1-based), atomically. The
/// header comments carry the mesh hash and the settings. Float writes 9 significant digits
/// (relative rounding <= 5e-9).
void write_matrix_market(const std::string& path, const SparseF& F, const FormFactorFileInfo& info,
                         ValuePrecision precision = ValuePrecision::Double);

/// Writes F (and its standard errors when present) in lambert's binary format, atomically.
void write_ff_binary(const std::string& path, const FormFactors& ff, const FormFactorFileInfo& info,
                     ValuePrecision precision = ValuePrecision::Double);

/// Reads a saved F (binary or Matrix Market, by content) and checks that it was made from
/// the same meshed scene: throws SceneError naming the file if the hash or size differ or
/// an entry is impossible (negative, non-finite, diagonal, repeated, a row sum above 1 by
/// more than the stored error), IoError if unreadable, truncated or corrupt. Every message
/// is one line naming the file and the first offending entry or line (docs/file-formats.md:
/// "Form-factor files"). Memory is bounded by the file's size before anything is allocated.
FormFactors read_form_factors(const std::string& path, std::uint64_t expected_mesh_hash,
                              std::int32_t expected_n, FormFactorFileInfo* info = nullptr);

/// read_form_factors from a seekable stream named `name` in messages. `expected_n` < 0
/// accepts any mesh (no identity check; for fuzzing and inspection).
FormFactors read_form_factors(std::istream& in, const std::string& name,
                              std::uint64_t expected_mesh_hash, std::int32_t expected_n,
                              FormFactorFileInfo* info = nullptr);

}  // namespace lambert
