#pragma once
// A glTF 2.0 scene written byte by byte (an independent reading of the format): the closed
// unit cube under one node with a transform, material "glow" (base colour 0.25, 0.5, 0.75;
// emissive 1, 0.5, 0), as a .gltf with its buffer in a data URI or as a GLB.

#include <cstdint>
#include <string>
#include <vector>

#include "io/base64.hpp"

namespace lambert::testing {

// The closed unit cube, two triangles per side, wound counter-clockwise seen from inside
// (fronts face the interior, as an enclosure's walls do).
inline const std::vector<float> kCubeCorners = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                                                0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
inline const std::vector<std::uint16_t> kCubeIndices = {0, 1, 2, 0, 2, 3, 4, 7, 6, 4, 6, 5,
                                                        0, 4, 5, 0, 5, 1, 3, 2, 6, 3, 6, 7,
                                                        0, 3, 7, 0, 7, 4, 1, 5, 6, 1, 6, 2};

// Each corner's colour (COLOR_0, when asked for): half its position.
inline std::vector<float> cube_colours() {
  std::vector<float> c;
  for (float x : kCubeCorners) c.push_back(0.5f * x);
  return c;
}

// Corners (96 bytes), indices (72), colours (96).
inline std::string cube_buffer() {
  std::string b(reinterpret_cast<const char*>(kCubeCorners.data()), kCubeCorners.size() * 4);
  b.append(reinterpret_cast<const char*>(kCubeIndices.data()), kCubeIndices.size() * 2);
  const std::vector<float> colours = cube_colours();
  b.append(reinterpret_cast<const char*>(colours.data()), colours.size() * 4);
  return b;
}

// The glTF JSON of the cube under one node with `matrix` (column-major, 16 numbers);
// `uri` empty: the buffer is the GLB's binary chunk; `colours`: with COLOR_0 per corner.
inline std::string cube_json(const std::string& matrix, const std::string& uri,
                             bool colours = false) {
  const std::string buffer = "{\"byteLength\":" + std::to_string(cube_buffer().size()) +
                             (uri.empty() ? std::string() : ",\"uri\":\"" + uri + "\"") + "}";
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],)"
         R"("nodes":[{"name":"box","mesh":0,"matrix":[)" +
         matrix + R"(]}],"meshes":[{"name":"cube","primitives":[{"attributes":{"POSITION":0)" +
         (colours ? R"(,"COLOR_0":2)" : "") +
         R"(},"indices":1,"material":0}]}],"materials":[{"name":"glow","pbrMetallicRoughness":)"
         R"({"baseColorFactor":[0.25,0.5,0.75,1],"metallicFactor":0},"emissiveFactor":[1,0.5,0]}],)"
         R"("buffers":[)" +
         buffer +
         R"(],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":96},)"
         R"({"buffer":0,"byteOffset":96,"byteLength":72},{"buffer":0,"byteOffset":168,)"
         R"("byteLength":96}],"accessors":[{"bufferView":0,"componentType":5126,"count":8,)"
         R"("type":"VEC3","min":[0,0,0],"max":[1,1,1]},{"bufferView":1,"componentType":5123,)"
         R"("count":36,"type":"SCALAR"},{"bufferView":2,"componentType":5126,"count":8,)"
         R"("type":"VEC3"}]})";
}

// Scale 2, then move by (1, 0, 0): the cube spans (1, 0, 0) - (3, 2, 2).
inline constexpr const char* kScaleAndMove = "2,0,0,0, 0,2,0,0, 0,0,2,0, 1,0,0,1";

inline std::string gltf_with_data_uri(const std::string& matrix, bool colours = false) {
  return cube_json(matrix, "data:application/octet-stream;base64," + base64_encode(cube_buffer()),
                   colours);
}

// A GLB: 12-byte header, the JSON chunk (padded with blanks), the BIN chunk (with zeros).
// `emissive_strength` > 0: the material carries KHR_materials_emissive_strength.
inline std::string glb(const std::string& matrix, double emissive_strength = 0.0) {
  std::string json = cube_json(matrix, ""), bin = cube_buffer();
  if (emissive_strength > 0.0) {
    const std::string factor = R"("emissiveFactor":[1,0.5,0])";
    json.insert(json.find(factor) + factor.size(),
                R"(,"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":)" +
                    std::to_string(emissive_strength) + "}}");
  }
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  auto u32 = [](std::uint32_t x) { return std::string(reinterpret_cast<const char*>(&x), 4); };
  return "glTF" + u32(2) + u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size())) +
         u32(static_cast<std::uint32_t>(json.size())) + "JSON" + json +
         u32(static_cast<std::uint32_t>(bin.size())) + std::string("BIN\0", 4) + bin;
}

}  // namespace lambert::testing
