#pragma once
// The tests' independent glTF reader: tinygltf (Debian's libtinygltf), which parses the GLB
// container and the JSON and checks every accessor against its buffer view.

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>
#include <string>
#include <vector>

namespace lambert::testing {

/// The model in a .glb's bytes; a parse error or warning fails the test.
inline tinygltf::Model parse_glb(const std::string& bytes) {
  tinygltf::TinyGLTF reader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = reader.LoadBinaryFromMemory(&model, &err, &warn,
                                              reinterpret_cast<const unsigned char*>(bytes.data()),
                                              static_cast<unsigned>(bytes.size()));
  EXPECT_TRUE(ok) << err;
  EXPECT_TRUE(err.empty()) << err;
  EXPECT_TRUE(warn.empty()) << warn;
  return model;
}

/// The floats of accessor `index` (tightly packed float data, as lambert writes them).
inline std::vector<float> glb_floats(const tinygltf::Model& m, int index) {
  const tinygltf::Accessor& a = m.accessors.at(index);
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  const tinygltf::BufferView& v = m.bufferViews.at(a.bufferView);
  const int components = a.type == TINYGLTF_TYPE_VEC3 ? 3 : 1;
  std::vector<float> out(a.count * components);
  EXPECT_LE(v.byteOffset + a.byteOffset + out.size() * sizeof(float), m.buffers.at(0).data.size());
  std::memcpy(out.data(), m.buffers[0].data.data() + v.byteOffset + a.byteOffset,
              out.size() * sizeof(float));
  return out;
}

/// The uint32 indices of accessor `index`.
inline std::vector<std::uint32_t> glb_indices(const tinygltf::Model& m, int index) {
  const tinygltf::Accessor& a = m.accessors.at(index);
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
  const tinygltf::BufferView& v = m.bufferViews.at(a.bufferView);
  std::vector<std::uint32_t> out(a.count);
  std::memcpy(out.data(), m.buffers[0].data.data() + v.byteOffset + a.byteOffset,
              out.size() * sizeof(std::uint32_t));
  return out;
}

/// The floats of attribute `name` of the first mesh's first primitive (empty when absent).
inline std::vector<float> glb_attribute(const tinygltf::Model& m, const std::string& name) {
  const auto& attributes = m.meshes.at(0).primitives.at(0).attributes;
  const auto it = attributes.find(name);
  return it == attributes.end() ? std::vector<float>{} : glb_floats(m, it->second);
}

}  // namespace lambert::testing
