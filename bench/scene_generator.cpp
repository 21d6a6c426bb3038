#include "bench/scene_generator.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/sampling.hpp"
#include "io/obj_loader.hpp"

namespace lambert::bench {
namespace {

using Box = std::pair<Eigen::Vector3d, Eigen::Vector3d>;  // min, max

/// Largest target accepted (10^8 triangles is ~10 GB of scene and far beyond the bench).
constexpr std::int64_t kMaxTarget = 100000000;
/// Fraction of the free volume the objects' ellipsoids fill: sparse enough that random
/// placement succeeds at once, dense enough that objects shadow each other.
constexpr double kFill = 0.08;

Material material(const char* name, double r, double g, double b) {
  Material m;
  m.name = name;
  m.rho = Eigen::Vector3d(r, g, b);
  return m;
}

// Bounding box of the faces of every surface whose name satisfies `pick`.
template <typename Pick>
Box surface_bounds(const Scene& s, Pick pick) {
  Box b{Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()),
        Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity())};
  for (const Face& f : s.faces) {
    if (!pick(s.surfaces[f.surface].name)) continue;
    for (auto v : f.vertices) {
      b.first = b.first.cwiseMin(s.vertices[v]);
      b.second = b.second.cwiseMax(s.vertices[v]);
    }
  }
  LAMBERT_CHECK(b.first.x() <= b.second.x(), "the built-in Cornell box lacks a surface");
  return b;
}

Box named_bounds(const Scene& s, const std::string& name) {
  return surface_bounds(s, [&](const std::string& n) { return n == name; });
}

// The empty room: from the inner sides of the walls (the measured walls are not quite
// planar or parallel: take the innermost vertex of each), the open front at the floor's
// front edge.
Box room_interior(const Scene& s) {
  const Box floor = named_bounds(s, "floor"), ceiling = named_bounds(s, "ceiling");
  const Box left = named_bounds(s, "left_wall"), right = named_bounds(s, "right_wall");
  const Box back = named_bounds(s, "back_wall");
  return {Eigen::Vector3d(right.second.x(), floor.second.y(), floor.first.z()),
          Eigen::Vector3d(left.first.x(), ceiling.first.y(), back.first.z())};
}

double distance_to_box(const Eigen::Vector3d& p, const Box& b) {
  return (p - p.cwiseMax(b.first).cwiseMin(b.second)).norm();
}

struct Placed {
  Eigen::Vector3d centre;
  double radius;  // of the bounding sphere
};

struct Ellipsoid {
  Eigen::Vector3d centre, semi_axes;  // semi-axes along x, y (up), z before the turn
  double turn = 0.0;                  // about +y, radians
  int k = 1;                          // octahedron face split: 8 k^2 triangles
};

// Triangles per object so that the remainder spreads evenly: k = round(sqrt(R / 8m)).
std::vector<int> split_counts(std::int64_t triangles, int objects) {
  std::vector<int> k(objects);
  std::int64_t left = triangles;
  for (int i = 0; i < objects; ++i) {
    const double per = static_cast<double>(left) / (8.0 * (objects - i));
    k[i] = std::max(1, static_cast<int>(std::lround(std::sqrt(std::max(per, 0.0)))));
    left -= 8LL * k[i] * k[i];
  }
  return k;
}

// Random sequential placement: a bounding sphere clear of the room's sides, the blocks and
// the objects placed so far by `gap`; on failure the object shrinks and tries again.
Ellipsoid place(Rng& rng, const Box& room, const std::vector<Box>& blocks,
                const std::vector<Placed>& placed, double r0, double gap, bool on_floor) {
  Ellipsoid e;
  double r = r0 * (0.7 + 0.6 * rng.uniform());
  const Eigen::Vector3d shape(0.6 + 0.4 * rng.uniform(), 0.6 + 0.4 * rng.uniform(),
                              0.6 + 0.4 * rng.uniform());
  e.turn = 2.0 * M_PI * rng.uniform();
  for (;;) {
    e.semi_axes = r * shape;
    const double R = e.semi_axes.maxCoeff();
    const Eigen::Vector3d lo = room.first + Eigen::Vector3d::Constant(R + gap);
    const Eigen::Vector3d hi = room.second - Eigen::Vector3d::Constant(R + gap);
    for (int attempt = 0; attempt < 2000 && (lo.array() < hi.array()).all(); ++attempt) {
      Eigen::Vector3d c(lo.x() + (hi.x() - lo.x()) * rng.uniform(),
                        lo.y() + (hi.y() - lo.y()) * rng.uniform(),
                        lo.z() + (hi.z() - lo.z()) * rng.uniform());
      // Resting: the lowest vertex (the -y pole) gap / 5 above the floor; its bounding sphere
      // may then dip below the floor, which the pole itself does not.
      if (on_floor) c.y() = room.first.y() + 0.2 * gap + e.semi_axes.y();
      bool clear = true;
      for (const Box& b : blocks) clear = clear && distance_to_box(c, b) > R + gap;
      for (const Placed& p : placed) clear = clear && (c - p.centre).norm() > R + p.radius + gap;
      if (clear) {
        e.centre = c;
        return e;
      }
    }
    r *= 0.85;
    LAMBERT_CHECK(r > 1e-3 * r0, "no room left for an object");
  }
}

// Appends a geodesic ellipsoid as surface `surface`. Octahedron vertices ±e_x, ±e_y, ±e_z;
// the face (sx e_x, sy e_y, sz e_z) is counter-clockwise about its outward normal when
// sx sy sz > 0 (else two corners swap). Grid point (i, j) of face (A, B, C) has the integer
// direction i A + j B + (k - i - j) C (|x| + |y| + |z| = k), so shared edge points of
// neighbouring faces are the same integer triple and become one vertex.
void add_ellipsoid(Scene& s, const Ellipsoid& e, std::int32_t surface) {
  const Eigen::Matrix3d map =
      Eigen::AngleAxisd(e.turn, Eigen::Vector3d::UnitY()).toRotationMatrix() *
      e.semi_axes.asDiagonal();
  std::map<std::array<int, 3>, std::int32_t> index;
  auto vertex = [&](const Eigen::Vector3i& d) {
    const std::array<int, 3> key{d.x(), d.y(), d.z()};
    auto [it, fresh] = index.emplace(key, static_cast<std::int32_t>(s.vertices.size()));
    if (fresh) s.vertices.push_back(e.centre + map * d.cast<double>().normalized());
    return it->second;
  };
  const int k = e.k;
  for (int sx = -1; sx <= 1; sx += 2) {
    for (int sy = -1; sy <= 1; sy += 2) {
      for (int sz = -1; sz <= 1; sz += 2) {
        Eigen::Vector3i A(sx, 0, 0), B(0, sy, 0), C(0, 0, sz);
        if (sx * sy * sz < 0) std::swap(A, B);
        auto at = [&](int i, int j) { return vertex(i * A + j * B + (k - i - j) * C); };
        // (i, j) -> position is affine per face with (C, A, B) at (0,0), (1,0), (0,1): both
        // grid triangles below keep the orientation of (C, A, B), i.e. of (A, B, C).
        for (int i = 0; i < k; ++i) {
          for (int j = 0; i + j < k; ++j) {
            s.faces.push_back({{at(i, j), at(i + 1, j), at(i, j + 1)}, surface, 0, {}});
            if (i + j + 2 <= k)
              s.faces.push_back({{at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)}, surface, 0, {}});
          }
        }
      }
    }
  }
}

// Every triangle of `surface` faces away from the ellipsoid's centre (fronts outward).
void check_outward(const Scene& s, const Ellipsoid& e, std::int32_t surface, std::size_t first) {
  for (std::size_t f = first; f < s.faces.size(); ++f) {
    const auto& v = s.faces[f].vertices;
    const Eigen::Vector3d &a = s.vertices[v[0]], &b = s.vertices[v[1]], &c = s.vertices[v[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    LAMBERT_CHECK(s.faces[f].surface == surface && n.dot((a + b + c) / 3.0 - e.centre) > 0.0,
                  "a generated triangle faces inward");
  }
}

}  // namespace

std::int64_t triangle_count(const Scene& scene) {
  std::int64_t n = 0;
  for (const Face& f : scene.faces) n += static_cast<std::int64_t>(f.vertices.size()) - 2;
  return n;
}

Scene cornell_with_objects(std::int64_t target_triangles, std::uint64_t seed) {
  Scene s = load_obj(builtin_cornell_box_path());
  const std::int64_t own = triangle_count(s);
  if (target_triangles < own + 8 || target_triangles > kMaxTarget)
    throw UsageError("generated scene: the target must lie in [" + std::to_string(own + 8) + ", " +
                     std::to_string(kMaxTarget) + "] triangles");
  s.source = "cornell_with_objects(" + std::to_string(target_triangles) + ", seed " +
             std::to_string(seed) + ")";
  const Box room = room_interior(s);
  std::vector<Box> blocks;
  for (const auto& surf : s.surfaces) {
    const std::string& n = surf.name;
    if (n.size() > 6 && n.compare(n.size() - 6, 6, "_block") == 0)
      blocks.push_back(named_bounds(s, n));
  }
  double free_volume = (room.second - room.first).prod();
  for (const Box& b : blocks) free_volume -= (b.second - b.first).prod();

  const std::int64_t wanted = target_triangles - own;
  const int objects = static_cast<int>(std::clamp<std::int64_t>(
      std::lround(std::sqrt(static_cast<double>(target_triangles)) / 2.0), 1, wanted / 8));
  // Mean semi-axis ~0.8 r0 per axis: M (4/3) pi (0.8 r0)^3 ~ kFill x free volume.
  const double r0 = std::cbrt(kFill * free_volume * 3.0 / (4.0 * M_PI * objects)) / 0.8;
  const double gap = 0.01 * (room.second - room.first).maxCoeff();
  // Floor objects first, as many as cover ~35 % of the free floor with their bounding
  // circles (at most half of them): more would not fit beside each other.
  double free_floor = (room.second.x() - room.first.x()) * (room.second.z() - room.first.z());
  for (const Box& b : blocks)
    free_floor -= (b.second.x() - b.first.x()) * (b.second.z() - b.first.z());
  const int on_floor = std::min<int>(
      objects / 2, static_cast<int>(0.35 * free_floor / (M_PI * (r0 + gap) * (r0 + gap))));

  const std::array<Material, 4> materials = {s.materials[0], material("blue", 0.15, 0.25, 0.6),
                                             material("yellow", 0.65, 0.55, 0.15),
                                             material("grey", 0.4, 0.4, 0.4)};
  std::array<std::int32_t, 4> material_index{};
  for (int m = 0; m < 4; ++m) {
    material_index[m] = -1;
    for (std::size_t i = 0; i < s.materials.size(); ++i)
      if (s.materials[i].name == materials[m].name)
        material_index[m] = static_cast<std::int32_t>(i);
    if (material_index[m] < 0) {
      material_index[m] = static_cast<std::int32_t>(s.materials.size());
      s.materials.push_back(materials[m]);
    }
  }

  Rng rng(hash_keys(seed, 0x5CE4E));
  std::vector<Placed> placed;
  const std::vector<int> k = split_counts(wanted, objects);
  for (int i = 0; i < objects; ++i) {
    Ellipsoid e = place(rng, room, blocks, placed, r0, gap, i < on_floor);
    e.k = k[i];
    placed.push_back({e.centre, e.semi_axes.maxCoeff()});
    char name[32];
    std::snprintf(name, sizeof name, "object_%04d", i);
    const auto surface = static_cast<std::int32_t>(s.surfaces.size());
    s.surfaces.push_back({name, material_index[i % 4]});
    const std::size_t first = s.faces.size();
    add_ellipsoid(s, e, surface);
    check_outward(s, e, surface, first);
  }
  return s;
}

}  // namespace lambert::bench
