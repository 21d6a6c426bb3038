#include "io/glb.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kModeLines = 1, kModeTriangles = 4;

void put_u32(std::string& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
}

// The BIN chunk under construction and the JSON's bufferViews/accessors describing it.
class Buffers {
 public:
  explicit Buffers(Json& gltf) : gltf_(gltf) {
    gltf_["bufferViews"] = Json::array();
    gltf_["accessors"] = Json::array();
  }
  // Appends `bytes` as a buffer view (4-byte aligned) and returns its index.
  int view(const void* data, std::size_t bytes, int target) {
    while (bin_.size() % 4 != 0) bin_.push_back('\0');
    Json v = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (target) v["target"] = target;
    bin_.append(static_cast<const char*>(data), bytes);
    gltf_["bufferViews"].push_back(v);
    return static_cast<int>(gltf_["bufferViews"].size()) - 1;
  }
  // A float accessor of `components` per element (with min/max when `bounds`).
  int floats(const std::vector<float>& values, int components, bool bounds) {
    const std::size_t count = values.size() / static_cast<std::size_t>(components);
    Json a = {{"bufferView", view(values.data(), values.size() * sizeof(float), kArrayBuffer)},
              {"componentType", kFloat},
              {"count", count},
              {"type", components == 1 ? "SCALAR" : "VEC3"}};
    if (bounds && count > 0) {
      std::vector<float> lo(components, std::numeric_limits<float>::max());
      std::vector<float> hi(components, std::numeric_limits<float>::lowest());
      for (std::size_t i = 0; i < values.size(); ++i) {
        const std::size_t c = i % static_cast<std::size_t>(components);
        lo[c] = std::min(lo[c], values[i]);
        hi[c] = std::max(hi[c], values[i]);
      }
      a["min"] = lo;
      a["max"] = hi;
    }
    return push(a);
  }
  int indices(const std::vector<std::uint32_t>& values) {
    return push({{"bufferView",
                  view(values.data(), values.size() * sizeof(std::uint32_t), kElementArrayBuffer)},
                 {"componentType", kUnsignedInt},
                 {"count", values.size()},
                 {"type", "SCALAR"}});
  }
  std::string& bin() { return bin_; }

 private:
  int push(const Json& accessor) {
    gltf_["accessors"].push_back(accessor);
    return static_cast<int>(gltf_["accessors"].size()) - 1;
  }
  Json& gltf_;
  std::string bin_;
};

bool allowed_name(const std::string& name) {
  if (name.size() > 1 && name[0] == '_') return true;
  if (name.rfind("COLOR_", 0) != 0 || name.size() == 6) return false;
  return std::all_of(name.begin() + 6, name.end(), [](char c) { return c >= '0' && c <= '9'; });
}

void check_finite(const std::vector<float>& values, const char* what) {
  for (const float v : values) LAMBERT_CHECK(std::isfinite(v), std::string("non-finite ") + what);
}

void check_content(const GlbContent& c) {
  LAMBERT_CHECK(c.positions.size() % 3 == 0, "positions are not 3 per vertex");
  const std::size_t n = c.positions.size() / 3;
  LAMBERT_CHECK(n < (std::size_t{1} << 31), "too many vertices for 32-bit indices");
  LAMBERT_CHECK(c.normals.empty() || c.normals.size() == c.positions.size(), "normals' size");
  LAMBERT_CHECK(c.triangles.size() % 3 == 0 && c.edges.size() % 2 == 0, "index counts");
  for (const std::uint32_t i : c.triangles) LAMBERT_CHECK(i < n, "triangle index out of range");
  for (const std::uint32_t i : c.edges) LAMBERT_CHECK(i < n, "edge index out of range");
  check_finite(c.positions, "position");
  check_finite(c.normals, "normal");
  for (const GlbAttribute& a : c.attributes) {
    LAMBERT_CHECK(allowed_name(a.name), "glTF does not allow the attribute name " + a.name);
    LAMBERT_CHECK(a.components == 1 || a.components == 3, "attribute components");
    LAMBERT_CHECK(a.values.size() == n * static_cast<std::size_t>(a.components),
                  "attribute " + a.name + " has the wrong size");
    check_finite(a.values, a.name.c_str());
  }
}

// The camera node: eye position and the rotation that turns -Z to the view direction and +Y
// to the up vector projected off it.
Json camera_node(const GlbCamera& cam) {
  const Eigen::Vector3d forward = (cam.look_at - cam.eye).normalized();
  const Eigen::Vector3d right = forward.cross(cam.up).normalized();
  const Eigen::Vector3d up = right.cross(forward);
  Eigen::Matrix3d r;
  r.col(0) = right;
  r.col(1) = up;
  r.col(2) = -forward;
  const Eigen::Quaterniond q(r);
  return {{"name", "camera"},
          {"camera", 0},
          {"translation", {cam.eye.x(), cam.eye.y(), cam.eye.z()}},
          {"rotation", {q.x(), q.y(), q.z(), q.w()}},
          {"extras",
           Json{{"target", Json::array({cam.look_at.x(), cam.look_at.y(), cam.look_at.z()})}}}};
}

}  // namespace

std::string glb_bytes(const GlbContent& c) {
  check_content(c);
  Json gltf = Json::object();
  gltf["asset"] = {{"version", "2.0"}, {"generator", c.generator}};
  if (!c.asset_extras.is_null()) gltf["asset"]["extras"] = c.asset_extras;
  gltf["extensionsUsed"] = Json::array({"KHR_materials_unlit"});
  Buffers buffers(gltf);

  Json attributes = {{"POSITION", buffers.floats(c.positions, 3, true)}};
  if (!c.normals.empty()) attributes["NORMAL"] = buffers.floats(c.normals, 3, false);
  for (const GlbAttribute& a : c.attributes)
    attributes[a.name] = buffers.floats(a.values, a.components, false);
  Json triangles = {{"attributes", attributes},
                    {"indices", buffers.indices(c.triangles)},
                    {"material", 0},
                    {"mode", kModeTriangles}};
  if (!c.primitive_extras.is_null()) triangles["extras"] = c.primitive_extras;

  const auto unlit = [](const char* name, double grey, bool double_sided) {
    return Json{{"name", name},
                {"pbrMetallicRoughness",
                 {{"baseColorFactor", {grey, grey, grey, 1.0}},
                  {"metallicFactor", 0.0},
                  {"roughnessFactor", 1.0}}},
                {"doubleSided", double_sided},
                {"extensions", {{"KHR_materials_unlit", Json::object()}}}};
  };
  // Every array is spelled Json::array: a braced list of one Json element is a copy of that
  // element, not an array of it (list-initialisation picks the copy constructor).
  gltf["materials"] = Json::array({unlit("radiosity", 1.0, true)});
  gltf["meshes"] =
      Json::array({Json{{"name", "radiosity"}, {"primitives", Json::array({triangles})}}});
  gltf["nodes"] = Json::array({Json{{"name", "radiosity"}, {"mesh", 0}}});
  if (!c.edges.empty()) {
    gltf["materials"].push_back(unlit("patch edges", 0.0, false));
    const Json lines = {{"attributes", Json{{"POSITION", attributes["POSITION"]}}},
                        {"indices", buffers.indices(c.edges)},
                        {"material", 1},
                        {"mode", kModeLines}};
    gltf["meshes"].push_back(Json{{"name", "patch edges"}, {"primitives", Json::array({lines})}});
    gltf["nodes"].push_back(
        Json{{"name", "patch edges"}, {"mesh", 1}, {"extras", Json{{"role", "patch edges"}}}});
  }
  if (c.camera) {
    const Json perspective = {{"yfov", c.camera->yfov_degrees * M_PI / 180.0},
                              {"aspectRatio", c.camera->aspect},
                              {"znear", c.camera->znear}};
    gltf["cameras"] = Json::array({Json{{"type", "perspective"}, {"perspective", perspective}}});
    gltf["nodes"].push_back(camera_node(*c.camera));
  }
  Json scene_nodes = Json::array();
  for (std::size_t k = 0; k < gltf["nodes"].size(); ++k) scene_nodes.push_back(k);
  gltf["scenes"] = Json::array({Json{{"nodes", scene_nodes}}});
  gltf["scene"] = 0;

  std::string& bin = buffers.bin();
  while (bin.size() % 4 != 0) bin.push_back('\0');
  gltf["buffers"] = Json::array({Json{{"byteLength", bin.size()}}});
  std::string json = gltf.dump(-1, ' ', false, Json::error_handler_t::replace);
  while (json.size() % 4 != 0) json.push_back(' ');

  std::string out;
  out.reserve(12 + 8 + json.size() + 8 + bin.size());
  put_u32(out, kGlbMagic);
  put_u32(out, 2);
  put_u32(out, static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  put_u32(out, static_cast<std::uint32_t>(json.size()));
  put_u32(out, kChunkJson);
  out += json;
  put_u32(out, static_cast<std::uint32_t>(bin.size()));
  put_u32(out, kChunkBin);
  out += bin;
  return out;
}

void write_glb(const std::string& path, const GlbContent& content) {
  const std::string bytes = glb_bytes(content);
  write_stream_atomically(
      path,
      [&](std::ostream& out) {
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      },
      true);
}

}  // namespace lambert
