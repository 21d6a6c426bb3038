#include "io/model_loader.hpp"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <dlfcn.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/json.hpp"
#include "io/soup_builder.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;

// assimp's C API, opened with dlopen on first use: linking it would load and relocate its
// 10 MB at every start of lambert, doubling the start-up of `lambert --version` (issue 36).
// Its scene structures are plain structs; their methods used here are inline.
struct Assimp {
  decltype(&aiImportFile) import_file;
  decltype(&aiImportFileFromMemory) import_memory;
  decltype(&aiReleaseImport) release;
  decltype(&aiGetErrorString) error;
  decltype(&aiIsExtensionSupported) extension_supported;
  decltype(&aiGetMaterialColor) colour;
  decltype(&aiGetMaterialFloatArray) floats;
  decltype(&aiGetMaterialString) string;
  decltype(&aiGetMaterialTextureCount) textures;
};

const Assimp& assimp() {
  static const Assimp api = [] {
    void* lib = dlopen(LAMBERT_ASSIMP_LIBRARY, RTLD_NOW | RTLD_LOCAL);
    if (!lib)
      throw IoError(std::string("reading glTF, FBX, COLLADA, ... needs assimp (Debian: ") +
                    "libassimp5; scripts/setup.sh installs it): " + dlerror());
    auto get = [lib](const char* name) {
      void* f = dlsym(lib, name);
      if (!f) throw IoError(std::string(LAMBERT_ASSIMP_LIBRARY) + " has no " + name);
      return f;
    };
    Assimp a;
    a.import_file = reinterpret_cast<decltype(a.import_file)>(get("aiImportFile"));
    a.import_memory = reinterpret_cast<decltype(a.import_memory)>(get("aiImportFileFromMemory"));
    a.release = reinterpret_cast<decltype(a.release)>(get("aiReleaseImport"));
    a.error = reinterpret_cast<decltype(a.error)>(get("aiGetErrorString"));
    a.extension_supported =
        reinterpret_cast<decltype(a.extension_supported)>(get("aiIsExtensionSupported"));
    a.colour = reinterpret_cast<decltype(a.colour)>(get("aiGetMaterialColor"));
    a.floats = reinterpret_cast<decltype(a.floats)>(get("aiGetMaterialFloatArray"));
    a.string = reinterpret_cast<decltype(a.string)>(get("aiGetMaterialString"));
    a.textures = reinterpret_cast<decltype(a.textures)>(get("aiGetMaterialTextureCount"));
    return a;
  }();
  return api;
}

// What the child process hands back: flat arrays, written and read field by field.
struct Soup {
  std::string error;  ///< assimp's complaint (then nothing else is set)
  std::vector<std::string> material_names;
  std::vector<double> material_values;  ///< per material: rho (3) then E (3)
  std::vector<std::string> surface_names;
  std::vector<std::int32_t> surface_material;
  std::vector<std::int32_t> face_surface, face_corners;  ///< per face: surface, corner count
  std::vector<double> corners;                           ///< 3 per corner, in face order
  /// With --vertex-colors-as-reflectance: per face the mean colour of its corners (3), or -1
  /// (3) when its mesh has no colours; empty otherwise.
  std::vector<double> face_rho;
  std::vector<std::int32_t> material_flags;  ///< per material: kTextured | ...
  std::int64_t points_lines = 0;             ///< point and line primitives skipped
};

constexpr std::int32_t kTextured = 1;  // its colour is a texture times the colour factor
constexpr std::int32_t kClamped = 2;   // a colour channel outside [0, 1] or not finite
constexpr std::int32_t kNoColour = 4;  // no diffuse or base colour at all

class Writer {
 public:
  template <class T>
  void pod(const T& x) {
    out.append(reinterpret_cast<const char*>(&x), sizeof(T));
  }
  void str(const std::string& s) {
    pod(static_cast<std::uint64_t>(s.size()));
    out += s;
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(static_cast<std::uint64_t>(v.size()));
    out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void strs(const std::vector<std::string>& v) {
    pod(static_cast<std::uint64_t>(v.size()));
    for (const auto& s : v) str(s);
  }
  std::string out;
};

// Reads what Writer wrote; a short or inconsistent message (a child that died mid-write) throws.
class Reader {
 public:
  explicit Reader(const std::string& in) : in_(in) {}
  template <class T>
  T pod() {
    T x;
    take(&x, sizeof(T));
    return x;
  }
  std::string str() {
    std::string s(count(1), '\0');
    take(s.data(), s.size());
    return s;
  }
  template <class T>
  std::vector<T> vec() {
    std::vector<T> v(count(sizeof(T)));
    take(v.data(), v.size() * sizeof(T));
    return v;
  }
  std::vector<std::string> strs() {
    std::vector<std::string> v(count(8));
    for (auto& s : v) s = str();
    return v;
  }
  bool done() const { return pos_ == in_.size(); }

 private:
  size_t count(size_t unit) {
    const auto n = pod<std::uint64_t>();
    if (n > (in_.size() - pos_) / unit) throw std::runtime_error("short message");
    return static_cast<size_t>(n);
  }
  void take(void* to, size_t bytes) {
    if (bytes > in_.size() - pos_) throw std::runtime_error("short message");
    if (bytes > 0) std::memcpy(to, in_.data() + pos_, bytes);
    pos_ += bytes;
  }
  const std::string& in_;
  size_t pos_ = 0;
};

std::string write_soup(const Soup& s) {
  Writer w;
  w.str(s.error);
  w.strs(s.material_names);
  w.vec(s.material_values);
  w.strs(s.surface_names);
  w.vec(s.surface_material);
  w.vec(s.face_surface);
  w.vec(s.face_corners);
  w.vec(s.corners);
  w.vec(s.face_rho);
  w.vec(s.material_flags);
  w.pod(s.points_lines);
  return w.out;
}

Soup read_soup(const std::string& bytes) {
  Reader r(bytes);
  Soup s;
  s.error = r.str();
  s.material_names = r.strs();
  s.material_values = r.vec<double>();
  s.surface_names = r.strs();
  s.surface_material = r.vec<std::int32_t>();
  s.face_surface = r.vec<std::int32_t>();
  s.face_corners = r.vec<std::int32_t>();
  s.corners = r.vec<double>();
  s.face_rho = r.vec<double>();
  s.material_flags = r.vec<std::int32_t>();
  s.points_lines = r.pod<std::int64_t>();
  if (!r.done()) throw std::runtime_error("bytes after the message");
  return s;
}

// ---- In the child: assimp's scene as a soup ----

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

Eigen::Vector3d material_colour(const aiMaterial& m, const char* key, unsigned type, unsigned index,
                                bool& found) {
  aiColor4D c;
  found = assimp().colour(&m, key, type, index, &c) == AI_SUCCESS;
  return found ? Eigen::Vector3d(c.r, c.g, c.b) : Eigen::Vector3d::Zero();
}

void add_materials(const aiScene& sc, Soup& s) {
  for (unsigned k = 0; k < sc.mNumMaterials; ++k) {
    const aiMaterial& m = *sc.mMaterials[k];
    aiString name;
    const bool named = assimp().string(&m, AI_MATKEY_NAME, &name) == AI_SUCCESS && name.length > 0;
    s.material_names.push_back(named ? name.C_Str() : "material_" + std::to_string(k));
    std::int32_t flags = 0;
    bool found = false;
    Eigen::Vector3d rho = material_colour(m, AI_MATKEY_BASE_COLOR, found);  // glTF's PBR colour
    if (!found) rho = material_colour(m, AI_MATKEY_COLOR_DIFFUSE, found);
    if (!found) flags |= kNoColour;
    if (!rho.allFinite() || rho.minCoeff() < 0.0 || rho.maxCoeff() > 1.0) flags |= kClamped;
    rho = rho.unaryExpr([](double x) { return std::isfinite(x) ? std::clamp(x, 0.0, 1.0) : 0.0; });
    Eigen::Vector3d e = material_colour(m, AI_MATKEY_COLOR_EMISSIVE, found);
    float strength = 1.0f;
    unsigned one = 1;
    if (assimp().floats(&m, AI_MATKEY_EMISSIVE_INTENSITY, &strength, &one) == AI_SUCCESS &&
        one == 1)
      e *= strength;
    if (!e.allFinite() || e.minCoeff() < 0.0) e = Eigen::Vector3d::Zero(), flags |= kClamped;
    if (assimp().textures(&m, aiTextureType_BASE_COLOR) +
            assimp().textures(&m, aiTextureType_DIFFUSE) >
        0)
      flags |= kTextured;
    s.material_flags.push_back(flags);
    s.material_values.insert(s.material_values.end(), rho.data(), rho.data() + 3);
    s.material_values.insert(s.material_values.end(), e.data(), e.data() + 3);
  }
}

void add_node(const aiScene& sc, const aiNode& node, const aiMatrix4x4& parent, bool colours,
              Soup& s, std::set<std::string>& used_names) {
  const aiMatrix4x4 m = parent * node.mTransformation;
  const bool mirrored = m.Determinant() < 0.0f;
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    if (node.mMeshes[k] >= sc.mNumMeshes) continue;
    const aiMesh& mesh = *sc.mMeshes[node.mMeshes[k]];
    std::string name = node.mName.length > 0 ? node.mName.C_Str() : "node";
    if (node.mNumMeshes > 1 || node.mName.length == 0)
      name += "/" + (mesh.mName.length > 0 ? std::string(mesh.mName.C_Str())
                                           : "mesh_" + std::to_string(node.mMeshes[k]));
    std::string unique = name;  // names are unique: one surface per mesh instance
    for (int n = 2; used_names.count(unique) > 0; ++n) unique = name + "#" + std::to_string(n);
    used_names.insert(unique);
    name = unique;
    const auto surface = static_cast<std::int32_t>(s.surface_names.size());
    s.surface_names.push_back(name);
    s.surface_material.push_back(mesh.mMaterialIndex < sc.mNumMaterials
                                     ? static_cast<std::int32_t>(mesh.mMaterialIndex)
                                     : -1);  // none: the default material
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices < 3) {
        ++s.points_lines;
        continue;
      }
      s.face_surface.push_back(surface);
      s.face_corners.push_back(static_cast<std::int32_t>(face.mNumIndices));
      Eigen::Vector3d rho = Eigen::Vector3d::Zero();
      for (unsigned c = 0; c < face.mNumIndices; ++c) {
        const unsigned corner = mirrored ? face.mNumIndices - 1 - c : c;
        const unsigned v = face.mIndices[corner];
        if (v >= mesh.mNumVertices) throw std::runtime_error("a face index out of range");
        const aiVector3D p = m * mesh.mVertices[v];
        s.corners.insert(s.corners.end(), {p.x, p.y, p.z});
        if (colours && mesh.HasVertexColors(0)) {
          const aiColor4D& colour = mesh.mColors[0][v];
          rho += Eigen::Vector3d(colour.r, colour.g, colour.b) / face.mNumIndices;
        }
      }
      if (colours && !mesh.HasVertexColors(0)) rho = Eigen::Vector3d::Constant(-1.0);
      if (colours) s.face_rho.insert(s.face_rho.end(), rho.data(), rho.data() + 3);
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    add_node(sc, *node.mChildren[c], m, colours, s, used_names);
}

Soup import(const std::string& path, bool colours) {
  Soup s;
  const Assimp& api = assimp();
  // A GLB or binary FBX under another name: assimp picks its reader by the extension, so
  // the bytes go with the format's (a GLB holds its buffers; an FBX references no files).
  std::string bytes, hint;
  {
    std::ifstream in(path, std::ios::binary);
    char head[18] = {};
    in.read(head, sizeof head);
    const std::string h(head, static_cast<size_t>(in.gcount()));
    const std::string ext = lower_extension(path);
    if (h.rfind("glTF", 0) == 0 && ext != ".glb") hint = "glb";
    if (h.rfind("Kaydara FBX Binary", 0) == 0 && ext != ".fbx") hint = "fbx";
    if (!hint.empty()) bytes = read_file_bytes(path);
  }
  if (bytes.size() > 0xffffffffu) {
    s.error = "a binary model over 4 GB";
    return s;
  }
  const aiScene* sc = hint.empty()
                          ? api.import_file(path.c_str(), aiProcess_ValidateDataStructure)
                          : api.import_memory(bytes.data(), static_cast<unsigned>(bytes.size()),
                                              aiProcess_ValidateDataStructure, hint.c_str());
  if (!sc || !sc->mRootNode) {
    const std::string why = api.error();
    s.error = why.empty() ? "not a scene the model reader (assimp) can read" : why;
    return s;
  }
  if (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE) {
    s.error = "an incomplete scene (no meshes, or only animations)";
    return s;
  }
  add_materials(*sc, s);
  std::set<std::string> used_names;
  add_node(*sc, *sc->mRootNode, aiMatrix4x4(), colours, s, used_names);
  api.release(sc);  // the child exits next; released all the same
  return s;
}

// ---- In lambert: the child, its message, the scene ----

// glTF's KHR_materials_emissive_strength (Blender's exports carry a lamp's strength there),
// which assimp 5.2 does not read: per glTF material, its name and emissive strength (1 where
// none). Empty when `path` is no glTF or its JSON does not parse (assimp has read it, so that
// leaves only what the JSON parser refuses: then the strengths stay 1).
std::vector<std::pair<std::string, double>> gltf_emissive_strengths(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[20] = {};
  in.read(head, sizeof head);
  const auto got = static_cast<size_t>(in.gcount());
  std::string text;
  if (got >= 4 && std::memcmp(head, "glTF", 4) == 0) {
    // GLB: the JSON chunk's length at byte 12, its type at 16, its text from 20 (only that
    // chunk is read, not the binary one).
    std::uint32_t length = 0;
    std::memcpy(&length, head + 12, 4);
    if (got < 20 || std::memcmp(head + 16, "JSON", 4) != 0) return {};
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec || length > size - 20) return {};
    text.resize(length);
    in.read(text.data(), static_cast<std::streamsize>(length));
    if (static_cast<size_t>(in.gcount()) != length) return {};
  } else if (lower_extension(path) == ".gltf") {
    text.assign(head, got);
    text.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  } else {
    return {};  // not a glTF
  }
  std::vector<std::pair<std::string, double>> out;
  const Json j = Json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("materials") || !j["materials"].is_array())
    return {};
  for (const Json& m : j["materials"]) {
    std::string name;
    double strength = 1.0;
    if (m.is_object() && m.contains("name") && m["name"].is_string()) name = m["name"];
    if (m.is_object() && m.contains("extensions") && m["extensions"].is_object()) {
      const Json& e = m["extensions"];
      if (e.contains("KHR_materials_emissive_strength") &&
          e["KHR_materials_emissive_strength"].is_object()) {
        const Json& s = e["KHR_materials_emissive_strength"];
        if (s.contains("emissiveStrength") && s["emissiveStrength"].is_number())
          strength = s["emissiveStrength"].get<double>();
      }
    }
    out.emplace_back(name, strength);
  }
  return out;
}

// Runs import(path) in a child process and returns its soup. `limit` bounds the wait.
Soup import_in_child(const std::string& path, bool colours, double limit_seconds) {
  int fds[2];
  if (pipe(fds) != 0)
    throw IoError(path + ": cannot start the model reader: " + std::strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]), close(fds[1]);
    throw IoError(path + ": cannot start the model reader: " + std::strerror(errno));
  }
  if (pid == 0) {  // the child: nothing of it returns; _exit skips the parent's atexit work
    close(fds[0]);
    std::string message;
    try {
      message = write_soup(import(path, colours));
    } catch (const std::exception& e) {
      Soup failed;
      failed.error = e.what();
      message = write_soup(failed);
    }
    size_t done = 0;
    while (done < message.size()) {
      const ssize_t n = write(fds[1], message.data() + done, message.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) _exit(3);
      done += static_cast<size_t>(n);
    }
    _exit(0);
  }
  close(fds[1]);
  std::string bytes;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_seconds);
  bool timed_out = false;
  char buffer[1 << 16];
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                          deadline - std::chrono::steady_clock::now())
                          .count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    bytes.append(buffer, static_cast<size_t>(n));
  }
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out)
    throw SceneError(path + ": the model reader (assimp) did not finish in " +
                     std::to_string(static_cast<int>(limit_seconds)) +
                     " s: the file is probably malformed");
  if (WIFSIGNALED(status))
    throw SceneError(path + ": the model reader (assimp) crashed on this file (signal " +
                     std::to_string(WTERMSIG(status)) + "): it is probably malformed");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw SceneError(path + ": the model reader (assimp) failed on this file");
  try {
    return read_soup(bytes);
  } catch (const std::exception&) {
    throw SceneError(path + ": the model reader (assimp) ended without a whole answer");
  }
}

}  // namespace

bool looks_like_model(const std::string& path, const std::string& head) {
  const std::string ext = lower_extension(path);
  if (ext == ".obj" || ext == ".stl" || ext == ".ply") return false;  // lambert's own readers
  if (head.rfind("glTF", 0) == 0 || head.rfind("Kaydara FBX Binary", 0) == 0) return true;
  if (ext.empty()) return false;
  try {
    return assimp().extension_supported(ext.c_str()) == AI_TRUE;
  } catch (const IoError&) {  // no assimp here: its common formats still say what they need
    for (const char* known : {".gltf", ".glb", ".fbx", ".dae", ".3ds", ".blend"})
      if (ext == known) return true;
    return false;
  }
}

Scene load_model(const std::string& path, LoadReport* report_out, const LoadOptions& options) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw IoError(path + ": cannot open: is a directory");
  const auto size = fs::file_size(path, ec);
  if (ec) throw IoError(path + ": cannot open: " + ec.message());
  const Soup s = import_in_child(path, options.vertex_colors_as_reflectance,
                                 60.0 + 4.0 * static_cast<double>(size) / 1e6);
  if (!s.error.empty()) {  // one line
    std::string why = s.error;
    std::replace(why.begin(), why.end(), '\n', ' ');
    throw SceneError(path + ": " + why);
  }

  LoadReport report;
  SceneBuilder out(path, report);
  Scene& scene = out.scene();
  const size_t materials = s.material_names.size();
  auto broken = [&] {
    return SceneError(path + ": the model reader (assimp) ended without a whole answer");
  };
  if (s.material_values.size() != 6 * materials || s.material_flags.size() != materials ||
      s.surface_material.size() != s.surface_names.size() ||
      s.face_corners.size() != s.face_surface.size() ||
      s.face_rho.size() != (options.vertex_colors_as_reflectance ? 3 * s.face_surface.size() : 0))
    throw broken();
  // What the file leaves to a default or lambert repairs: a warning with the count, or with
  // --strict a refusal.
  auto warn = [&](const std::string& msg) {
    if (options.strict) throw SceneError(msg + " (refused with --strict)");
    log_warn(msg);
    report.warnings.push_back(msg);
  };
  // --max-reflectance clamps (with a warning); --strict refuses rho = 1 (I - rho F singular).
  int limited = 0, lossless = 0;
  auto limit = [&](Eigen::Vector3d rho) {
    if (options.max_reflectance > 0 && rho.maxCoeff() > options.max_reflectance)
      rho = rho.cwiseMin(options.max_reflectance), ++limited;
    if (rho.maxCoeff() >= 1.0) ++lossless;
    return rho;
  };
  // The materials the surfaces use (assimp adds a default one of its own), in file order,
  // then lambert's default for meshes without any.
  for (const std::int32_t m : s.surface_material)
    if (m < -1 || m >= static_cast<std::int32_t>(materials)) throw broken();
  std::vector<std::int32_t> index(materials + 1, -1);  // file material (+1) -> scene's
  for (const std::int32_t m : s.surface_material) index[m + 1] = 0;
  int textured = 0, clamped = 0, uncoloured = 0;
  // assimp lists a glTF's materials in the file's order (and may add a default one after).
  const auto strengths = gltf_emissive_strengths(path);
  int strengthened = 0;
  for (size_t m = 0; m < materials; ++m) {
    if (index[m + 1] < 0) continue;
    index[m + 1] = static_cast<std::int32_t>(scene.materials.size());
    const double* v = s.material_values.data() + 6 * m;
    const std::int32_t flags = s.material_flags[m];
    Eigen::Vector3d rho(v[0], v[1], v[2]);
    // A texture's mean is not known here: its colour factor scales the default reflectance.
    if (flags & kNoColour) {
      rho = options.default_reflectance, ++uncoloured;
      report.default_material_used = true;
    } else if (flags & kTextured) {
      rho = rho.cwiseProduct(options.default_reflectance), ++textured;
    }
    if (flags & kClamped) ++clamped;
    Eigen::Vector3d e(v[3], v[4], v[5]);
    if (m < strengths.size() &&
        (strengths[m].first.empty() || strengths[m].first == s.material_names[m]) &&
        strengths[m].second != 1.0) {
      if (!(std::isfinite(strengths[m].second) && strengths[m].second >= 0.0))
        throw SceneError(path + ": material '" + s.material_names[m] +
                         "': emissiveStrength must be a finite number >= 0");
      e *= strengths[m].second, ++strengthened;
    }
    scene.materials.push_back({s.material_names[m], limit(rho), e});
  }
  if (index[0] == 0) {
    index[0] = static_cast<std::int32_t>(scene.materials.size());
    scene.materials.push_back({"default", options.default_reflectance, Eigen::Vector3d::Zero()});
    report.default_material_used = true;
  }
  for (size_t k = 0; k < s.surface_names.size(); ++k) {
    const std::int32_t surface = out.surface(s.surface_names[k]);
    if (static_cast<size_t>(surface) != k) throw broken();  // the names are unique
    scene.surfaces[surface].material = index[s.surface_material[k] + 1];
  }
  size_t next = 0, coloured = 0;
  std::vector<Eigen::Vector3d> poly;
  for (size_t f = 0; f < s.face_surface.size(); ++f) {
    const auto n = static_cast<size_t>(s.face_corners[f]);
    if (s.face_corners[f] < 3 || 3 * (next + n) > s.corners.size() || s.face_surface[f] < 0 ||
        static_cast<size_t>(s.face_surface[f]) >= s.surface_names.size())
      throw broken();
    poly.clear();
    for (size_t c = 0; c < n; ++c, ++next) {
      const Eigen::Vector3d p(s.corners[3 * next], s.corners[3 * next + 1],
                              s.corners[3 * next + 2]);
      if (!p.allFinite())
        throw SceneError(path + ": " + s.surface_names[s.face_surface[f]] +
                         ": a non-finite vertex coordinate");
      poly.push_back(p);
    }
    const size_t before = scene.faces.size();
    out.add_polygon(poly, s.face_surface[f],
                    s.surface_names[s.face_surface[f]] + " face " + std::to_string(f + 1));
    if (!s.face_rho.empty() && s.face_rho[3 * f] >= 0.0) {  // the mean of its corners' colours
      const Eigen::Vector3d rho =
          limit(Eigen::Vector3d(s.face_rho[3 * f], s.face_rho[3 * f + 1], s.face_rho[3 * f + 2])
                    .cwiseMax(0.0)
                    .cwiseMin(1.0));
      for (size_t k = before; k < scene.faces.size(); ++k) scene.faces[k].rho = rho;
      ++coloured;
    }
  }
  if (strengthened > 0)
    log_info(path + ": " + std::to_string(strengthened) +
             " material(s) emit their glTF emissive colour times emissiveStrength");
  if (options.vertex_colors_as_reflectance && coloured == 0)
    warn(path + ": --vertex-colors-as-reflectance: no mesh of the file has vertex colours");
  if (limited > 0)
    warn(path + ": " + std::to_string(limited) + " reflectance(s) clamped to --max-reflectance " +
         std::to_string(options.max_reflectance));
  if (lossless > 0)
    warn(path + ": " + std::to_string(lossless) +
         " reflectance(s) reach 1 in a channel, where light is never absorbed (a closed "
         "scene's I - rho F is then singular)");
  if (s.points_lines > 0)
    warn(path + ": " + std::to_string(s.points_lines) +
         " point and line primitive(s) skipped (radiosity meshes surfaces only)");
  if (textured > 0)
    warn(path + ": " + std::to_string(textured) +
         " material(s) colour their surface with a texture, which lambert does not sample: "
         "their reflectance is the colour factor times --default-reflectance");
  if (uncoloured > 0)
    warn(path + ": " + std::to_string(uncoloured) +
         " material(s) without a colour take --default-reflectance");
  if (clamped > 0)
    warn(path + ": " + std::to_string(clamped) +
         " material(s) with a colour channel outside [0, 1] or not finite: clamped");
  if (scene.faces.empty() && report.degenerate_faces_dropped == 0)
    throw SceneError(path + ": no polygon faces (only points, lines or an empty scene)");
  Scene loaded = out.finish(options, 1);  // glTF and assimp's other formats: y up
  add_camera_sidecar(loaded, path);
  if (report_out) *report_out = std::move(report);
  return loaded;
}

}  // namespace lambert
