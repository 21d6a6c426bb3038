#pragma once
// STL (stereolithography) scene loading: ASCII and binary, told apart by content, read by
// lambert's own strict reader (docs/scenes.md says why no Debian library is used).

#include <string>

#include "geometry/scene.hpp"
#include "io/obj_loader.hpp"

namespace lambert {

/// The two STL encodings.
enum class StlKind { Ascii, Binary };

/// True when the bytes `head` (the start of a file, at least its first 84 bytes when it has
/// them) of a file of `size` bytes are STL: a binary STL's size is 84 + 50 n with n the count
/// at bytes 80..83; an ASCII STL starts (after blanks) with the keyword `solid`; a file with a
/// NUL byte among its first 84 is taken for a (broken) binary STL, so that a truncated binary
/// is reported as one (no text format lambert reads holds NUL bytes).
bool looks_like_stl(const std::string& head, std::uint64_t size);

/// Which encoding `bytes` hold: binary when the size rule holds (even if the header starts
/// with "solid", as many exporters write), ASCII when the text starts with `solid` and holds
/// no NUL byte, binary otherwise (then a size mismatch is the error).
StlKind stl_kind(const std::string& bytes);

/// Loads an STL file. ASCII: each `solid NAME ... endsolid` block is a surface named NAME
/// (blocks with the same name share one; an unnamed block is named after the file stem, with
/// its 1-based block number when there are several). Binary: one surface per connected
/// component (facets sharing a corner position exactly), named STEM when there is one, else
/// STEM_1, STEM_2, ... in order of their first facet. Facets are oriented by their vertex
/// order (counter-clockwise about the front); a stored normal pointing to the back side of the
/// winding (a negative dot product) is counted and warned about once per file; a zero normal
/// is accepted silently. Zero-area facets are dropped as the OBJ loader drops faces (counted,
/// one warning). Every surface gets the default material (options.default_reflectance, no
/// emission), then `--emit` rules apply. A camera sidecar `<stem>.camera` is read as for OBJ.
/// Throws IoError (missing file) or SceneError ("file:line: what" for ASCII, "file: facet K:
/// what" for binary) for a truncated binary file, a facet count that disagrees with the size,
/// a non-finite or malformed number, an unexpected keyword, or a file without facets.
Scene load_stl(const std::string& path, LoadReport* report = nullptr,
               const LoadOptions& options = {});

/// load_stl from the file's bytes, named `name` in messages (no camera sidecar). For tests
/// and fuzzing.
Scene load_stl_bytes(const std::string& bytes, const std::string& name,
                     LoadReport* report = nullptr, const LoadOptions& options = {});

/// Loads a scene file, its format told apart by content (PLY, STL; GLB and binary FBX by
/// their first bytes), then by an extension assimp reads (io/model_loader.hpp), else OBJ:
/// the one place where a command's SCENE is opened.
Scene load_scene_path(const std::string& path, LoadReport* report = nullptr,
                      const LoadOptions& options = {});

}  // namespace lambert
