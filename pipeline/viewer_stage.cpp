#include "pipeline/viewer_stage.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "core/atomic_file.hpp"
#include "io/viewer_page.hpp"

namespace lambert {
namespace {

std::vector<float> as_floats(const Eigen::MatrixX3d& values) {
  std::vector<float> out(static_cast<std::size_t>(values.rows()) * 3);
  for (Eigen::Index k = 0; k < values.rows(); ++k)
    for (int c = 0; c < 3; ++c) out[3 * k + c] = static_cast<float>(values(k, c));
  return out;
}

// The shading vertices' values of patch values P with the solution's per-surface rescale
// (`scale`, per surface): linear in P (the header's Linearity).
Eigen::MatrixX3d vertex_values(const PatchMesh& mesh, const Eigen::MatrixX3d& P,
                               const std::vector<SurfacePower>& scale) {
  VertexField f = interpolate_to_vertices(mesh, P, VertexInterpolation::AreaWeighted);
  for (std::int32_t k = 0; k < f.size(); ++k)
    f.values.row(k) = f.values.row(k).cwiseProduct(scale.at(f.surface[k]).scale.transpose());
  return f.values;
}

}  // namespace

GlbContent viewer_glb(const ViewerInputs& in, double* linearity_error) {
  const PatchMesh& mesh = in.mesh;
  const VertexField& field = in.shaded.field;
  // The solution's vertex values and the per-surface rescale the bases share.
  std::vector<SurfacePower> power = in.shaded.power;
  Eigen::MatrixX3d solution = field.values;
  // Exact direct light and the linear fit are not linear in the lights: the viewer's bases
  // (which it sums) are conservative ones.
  const bool own = in.shaded.interpolation == "exact-direct" || in.shaded.interpolation == "linear";
  if (own)
    solution =
        interpolate_to_vertices(mesh, in.B, VertexInterpolation::Conservative, &power).values;

  GlbContent c;
  c.generator = std::string("lambert ") + LAMBERT_VERSION;
  const std::int32_t n = field.size();
  c.positions.resize(3 * static_cast<std::size_t>(n));
  c.normals.resize(3 * static_cast<std::size_t>(n));
  for (std::int32_t k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) {
      c.positions[3 * k + a] = static_cast<float>(field.positions[k][a]);
      c.normals[3 * k + a] = static_cast<float>(field.normals[k][a]);
    }
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const auto& v = field.patch_corners[i];
    const int m = mesh.patches[i].vertex_count;
    const auto u = [&](int k) { return static_cast<std::uint32_t>(v[k]); };
    c.triangles.insert(c.triangles.end(), {u(0), u(1), u(2)});
    if (m == 4) c.triangles.insert(c.triangles.end(), {u(0), u(2), u(3)});
    for (int k = 0; k < m; ++k) edges.insert(std::minmax(u(k), u((k + 1) % m)));
  }
  for (const auto& [a, b] : edges) c.edges.insert(c.edges.end(), {a, b});

  c.attributes.push_back({"COLOR_0", 3, as_floats(solution)});
  Json emitters = Json::array(), names = Json::array();
  Eigen::MatrixX3d sum = Eigen::MatrixX3d::Zero(n, 3);
  for (std::size_t k = 0; k < in.bases.size(); ++k) {
    const EmitterBasis& b = in.bases[k];
    const Eigen::MatrixX3d values = vertex_values(mesh, b.B, power);
    sum += values;
    const std::string attribute = "COLOR_" + std::to_string(k + 1);
    c.attributes.push_back({attribute, 3, as_floats(values)});
    emitters.push_back({{"name", b.name},
                        {"kind", b.kind},
                        {"attribute", attribute},
                        {"surfaces", b.surfaces},
                        {"power", {b.power[0], b.power[1], b.power[2]}}});
    names.push_back(b.name);
  }
  double error = 0.0;
  if (!in.bases.empty()) {
    const double scale = solution.cwiseAbs().maxCoeff();
    error = scale > 0.0 ? (sum - solution).cwiseAbs().maxCoeff() / scale : 0.0;
  }
  if (linearity_error) *linearity_error = error;

  const Camera& cam = in.camera;
  GlbCamera gc;
  gc.eye = cam.eye;
  gc.look_at = cam.look_at;
  gc.up = cam.up;
  gc.yfov_degrees = cam.vfov_degrees;
  gc.aspect = static_cast<double>(cam.width) / cam.height;
  gc.znear = 1e-4 * mesh.scale;
  c.camera = gc;

  Json lambert = {{"quantity", "radiosity"},
                  {"units", "W/m^2 of the scene's length unit; radiance shown = B / pi"},
                  {"interpolation", own ? "conservative" : in.shaded.interpolation},
                  {"exposure_ev", in.ev},
                  {"scene", in.scene},
                  {"settings", in.settings},
                  {"emitters", emitters}};
  if (const Daylight& light = in.daylight; light.has_sky())
    lambert["sky_radiance"] = {light.sky[0], light.sky[1], light.sky[2]};
  if (in.bases.empty())
    lambert["no_relighting"] = in.no_relighting;
  else
    lambert["linearity_error"] = error;
  c.asset_extras = {{"lambert", lambert}};
  c.primitive_extras = {{"emitters", names}};
  return c;
}

GlbContent heat_viewer_glb(const HeatViewerInputs& in) {
  const std::int32_t n = in.mesh.size();
  Eigen::MatrixX3d J(n, 3), Tq(n, 3);
  J.col(0) = J.col(1) = J.col(2) = in.J;
  Tq.col(0) = in.T;
  Tq.col(1) = in.q;
  Tq.col(2).setZero();
  ShadedField shaded;
  shaded.field = interpolate_to_vertices(in.mesh, J, VertexInterpolation::AreaWeighted);
  shaded.interpolation = "area";
  const VertexField tq = interpolate_to_vertices(in.mesh, Tq, VertexInterpolation::AreaWeighted);
  // The picture of J: the PNG's key-value exposure of its mean radiance (J / pi).
  const double mean = in.J.size() ? in.J.cwiseAbs().mean() / M_PI : 0.0;
  const double ev = mean > 0.0 ? std::log2(0.36 / mean) : 0.0;
  static const std::vector<EmitterBasis> kNone;
  const Daylight none;
  GlbContent c =
      viewer_glb({in.mesh, none, in.scene, J, shaded, kNone,
                  "a heat result is shown by temperature and flux", in.camera, ev, in.settings});
  std::vector<float> T(static_cast<std::size_t>(tq.size())), q(T.size());
  std::int64_t undefined = 0;
  for (std::int32_t k = 0; k < tq.size(); ++k) {
    const bool ok = std::isfinite(tq.values(k, 0));
    undefined += ok ? 0 : 1;
    T[k] = ok ? static_cast<float>(tq.values(k, 0)) : 0.0f;
    q[k] = std::isfinite(tq.values(k, 1)) ? static_cast<float>(tq.values(k, 1)) : 0.0f;
  }
  c.attributes.push_back({"_TEMPERATURE", 1, std::move(T)});
  c.attributes.push_back({"_HEAT_FLUX", 1, std::move(q)});
  Json& lambert = c.asset_extras["lambert"];
  lambert["quantity"] = "heat";
  lambert["units"] = "temperature K, heat flux W/m^2 (net, leaving), radiosity W/m^2";
  lambert["default_mode"] = "temperature";
  lambert["undefined_temperature_vertices"] = undefined;
  return c;
}

std::vector<std::string> write_viewer(const GlbContent& glb, const std::string& glb_path,
                                      const std::string& page_path, const std::string& title) {
  const std::string bytes = glb_bytes(glb);
  std::vector<std::string> written;
  if (!glb_path.empty()) {
    write_stream_atomically(
        glb_path,
        [&](std::ostream& out) {
          out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        },
        true);
    written.push_back(glb_path);
  }
  if (!page_path.empty()) {
    write_viewer_page(page_path, bytes, title);
    written.push_back(page_path);
  }
  return written;
}

}  // namespace lambert
