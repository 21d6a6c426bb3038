#pragma once
// Base64 (RFC 4648, standard alphabet, '=' padding): the embedded glb of the viewer page and
// the binary DataArrays of VTU files.

#include <string>
#include <string_view>

namespace lambert {

/// The base64 text of `bytes`, padded with '=' to a multiple of 4 characters.
std::string base64_encode(std::string_view bytes);

/// The bytes of a base64 text: digits, then at most two '=' at the end. Throws IoError on any
/// other character, a length that is not a multiple of 4, or padding before the end.
std::string base64_decode(std::string_view text);

}  // namespace lambert
