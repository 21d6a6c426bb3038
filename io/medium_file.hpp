#pragma once
// The heterogeneous medium format read by --medium-grid (docs/media.md):
//
//   # comments and blank lines anywhere
//   bounds X0 Y0 Z0 X1 Y1 Z1
//   resolution NX NY NZ
//   then NX*NY*NZ voxel lines, x fastest, then y, then z:
//   SA_R SA_G SA_B SS_R SS_G SS_B E_R E_G E_B
//
// σa, σs in 1/scene unit, e in W per scene unit³ (geometry/media/medium.hpp); σa + σs must be grey.

#include <istream>
#include <string>

#include "geometry/media/medium.hpp"

namespace lambert {

/// Reads and validates a medium grid file. Throws IoError when it cannot be read and
/// SceneError naming the file and line for a malformed, negative or non-finite value, a
/// missing header, or a voxel count that does not match the resolution.
Medium read_medium_grid(const std::string& path);

/// The same from a stream named `name` in messages (the medium's `source`).
Medium read_medium_grid_stream(std::istream& in, const std::string& name);

}  // namespace lambert
