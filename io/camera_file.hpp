#pragma once
// The camera sidecar `<scene>.camera`: the default view of a scene, one `key values` line
// per setting.

#include <istream>
#include <string>

#include "geometry/render/camera.hpp"

namespace lambert {

/// Reads a camera sidecar: `eye X Y Z` and `look_at X Y Z` (required), `up X Y Z`, and
/// either `vfov DEGREES` or `focal_mm F` with `film_mm W`; blank lines and `#` comments
/// are skipped. Refused with a SceneError "FILE:LINE: what" (exit 1): an unknown key, a
/// repeated key, missing or extra numbers (trailing text), a number that is not finite,
/// `focal_mm` without `film_mm` (or the reverse), `vfov` together with them, a field of
/// view outside (0, 180) degrees, `look_at` equal to `eye`, `up` parallel to the view.
/// IoError if the file cannot be read. Lines are bounded (io/line_reader).
Camera read_camera_file(const std::string& path);

/// read_camera_file from a stream named `name` in messages (tests and fuzzing).
Camera read_camera_stream(std::istream& in, const std::string& name);

}  // namespace lambert
