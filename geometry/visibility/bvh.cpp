#include "geometry/visibility/bvh.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <string>

#include "core/error.hpp"
#include "core/log.hpp"

namespace lambert {
namespace {

// Embree's error callback runs inside Embree's C frames: it must log, never throw.
void embree_error(void*, RTCError code, const char* str) noexcept {
  try {
    log_warn(std::string("embree error ") + std::to_string(static_cast<int>(code)) + ": " +
             (str ? str : ""));
  } catch (...) {
    // Logging failed (out of memory): nothing safe is left to do inside Embree's frames;
    // check_device() still reports the error code after the call returns.
  }
}

void check_device(RTCDevice device, const char* what) {
  const RTCError err = rtcGetDeviceError(device);
  if (err != RTC_ERROR_NONE)
    throw Error(std::string("embree: ") + what + " failed (error " +
                std::to_string(static_cast<int>(err)) + ")");
}

}  // namespace

// Named (not anonymous) because Bvh::Impl holds them: a class with external linkage may not
// hold a type of an anonymous namespace once this file is compiled inside a unity batch.
namespace bvh_detail {
struct DeviceDeleter {
  void operator()(RTCDeviceTy* d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
  void operator()(RTCSceneTy* s) const { rtcReleaseScene(s); }
};
}  // namespace bvh_detail
using bvh_detail::DeviceDeleter;
using bvh_detail::SceneDeleter;

namespace {

std::atomic<std::int64_t> g_builds{0};

// The process's Embree devices, one per thread count, created on first use and released at
// exit (after every Bvh: a Bvh keeps its device alive through the shared pointer).
struct DeviceRegistry {
  std::mutex mutex;
  std::map<int, std::shared_ptr<RTCDeviceTy>> devices;
};
DeviceRegistry& device_registry() {
  static DeviceRegistry registry;
  return registry;
}

std::shared_ptr<RTCDeviceTy> process_device(int threads) {
  DeviceRegistry& r = device_registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  auto& devices = r.devices;
  std::shared_ptr<RTCDeviceTy>& d = devices[threads];
  if (d) return d;
  const std::string config =
      "verbose=0" + (threads > 0 ? ",threads=" + std::to_string(threads) : std::string());
  d.reset(rtcNewDevice(config.c_str()), DeviceDeleter());
  if (!d) {
    devices.erase(threads);
    throw Error("embree: cannot create device");
  }
  rtcSetDeviceErrorFunction(d.get(), embree_error, nullptr);
  return d;
}

}  // namespace

// Embree works in single precision, and its intersection tests multiply three coordinates
// (cross products dotted with the direction): scene coordinates near 1e13 overflow float
// there (3.4e38) and near 1e-13 underflow, so occlusion was lost and the Cornell box scaled
// by 3e10 or 1e-20 gave wrong factors (issue 33, item 4). The BVH therefore holds the scene
// scaled by a power of two, 2^-e with the largest |coordinate| in [2^(e-1), 2^e): inside
// (-1, 1), exactly (a power-of-two scale commutes with rounding), and every query is scaled
// by the same factor (origin and direction alike, so ray parameters t are unchanged).
// kMaxCoordinate, kMinCoordinate: the scene magnitudes whose single-precision images stay
// normal numbers with room for the callers' arithmetic (float spans 1.2e-38 .. 3.4e38).
constexpr double kMaxCoordinate = 1e30, kMinCoordinate = 1e-30;
// Embree refuses (asserts on) rays whose origin or direction exceed 1.844e18 in magnitude.
constexpr float kMaxRayComponent = 1e18f;

struct Bvh::Impl {
  std::shared_ptr<RTCDeviceTy> device;
  std::unique_ptr<RTCSceneTy, SceneDeleter> scene;  // released before the device
  int exponent = 0;                                 // the BVH holds the scene scaled by 2^exponent
  double scale = 1.0;                               // 2^exponent
};

namespace {
// A query in the BVH's frame: origin and direction scaled by 2^exponent, and the direction
// by a further 2^-shift when its length is far from 1 (a unit camera ray in a tiny scene),
// ray parameters by 2^shift to match. Every factor is a power of two: nothing is rounded.
struct FrameRay {
  Eigen::Vector3f o, d;
  int shift = 0;  // t in the BVH's frame = t * 2^shift
};

// Throws SceneError for a ray Embree cannot take (a medium box or sensor point far outside
// the scene, a non-finite origin).
//
// v * 2^exponent is computed as float(double(v) * scale), scale = 2^exponent: the product is
// exact in double (|exponent| <= ~100 for coordinates within 1e-30 .. 1e30) and the one
// rounding to float is std::ldexp's, so the rays are the same floats without a libm call
// per component (nine per ray were ~15 % of an occlusion query).
FrameRay to_bvh_frame(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                      double scale) {
  auto scaled = [](float v, double by) { return static_cast<float>(static_cast<double>(v) * by); };
  FrameRay r;
  for (int k = 0; k < 3; ++k) r.o[k] = scaled(origin[k], scale);
  const float length = scaled(direction.cwiseAbs().maxCoeff(), scale);
  if (length > 0.0f && std::isfinite(length) && (length > 0x1p30f || length < 0x1p-30f))
    r.shift = std::ilogb(length) + 1;
  const double dscale = r.shift == 0 ? scale : std::ldexp(scale, -r.shift);
  for (int k = 0; k < 3; ++k) r.d[k] = scaled(direction[k], dscale);
  if (!(r.o.cwiseAbs().maxCoeff() <= kMaxRayComponent &&
        r.d.cwiseAbs().maxCoeff() <= kMaxRayComponent))
    throw SceneError("a ray from (" + std::to_string(origin.x()) + ", " +
                     std::to_string(origin.y()) + ", " + std::to_string(origin.z()) +
                     ") lies too far outside the scene for the ray tracer (more than 1e18 "
                     "times the scene's size; a medium box or point far beyond the geometry?)");
  return r;
}
}  // namespace

std::int64_t Bvh::builds() { return g_builds.load(); }

std::int64_t Bvh::devices() {
  DeviceRegistry& r = device_registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  return static_cast<std::int64_t>(r.devices.size());
}

Bvh::Bvh(const PatchMesh& mesh, int threads) : impl_(std::make_unique<Impl>()) {
  double largest = 0.0;
  for (const auto& v : mesh.vertices) largest = std::max(largest, v.cwiseAbs().maxCoeff());
  if (!mesh.vertices.empty()) {
    if (!(largest <= kMaxCoordinate) || largest < kMinCoordinate)
      throw SceneError("the scene's coordinates reach " + std::to_string(largest) +
                       " in magnitude: the ray tracer (single precision) needs them between "
                       "1e-30 and 1e30; rescale the scene (e.g. other length units)");
    if (largest > 0.0) impl_->exponent = -(std::ilogb(largest) + 1);
    impl_->scale = std::ldexp(1.0, impl_->exponent);
  }
  ++g_builds;
  impl_->device = process_device(threads);
  RTCDevice device = impl_->device.get();
  impl_->scene.reset(rtcNewScene(device));
  check_device(device, "rtcNewScene");
  RTCScene scene = impl_->scene.get();
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);

  // One quad geometry; a triangle is the degenerate quad (v0, v1, v2, v2). Primitive id
  // equals patch index.
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
  check_device(device, "rtcNewGeometry");
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), mesh.patches.size()));
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    check_device(device, "rtcSetNewGeometryBuffer");
    throw Error("embree: cannot allocate geometry buffers");
  }
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    for (int d = 0; d < 3; ++d)
      vb[3 * v + d] = static_cast<float>(std::ldexp(mesh.vertices[v][d], impl_->exponent));
  for (size_t p = 0; p < mesh.patches.size(); ++p) {
    const auto& patch = mesh.patches[p];
    for (int k = 0; k < 4; ++k)
      ib[4 * p + k] = static_cast<unsigned>(patch.vertices[k < patch.vertex_count ? k : 2]);
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  check_device(device, "rtcCommitScene");
}

Bvh::~Bvh() = default;

bool Bvh::occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float tnear,
                   float tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  const FrameRay f = to_bvh_frame(origin, direction, impl_->scale);
  RTCRay ray;
  ray.org_x = f.o.x();
  ray.org_y = f.o.y();
  ray.org_z = f.o.z();
  ray.dir_x = f.d.x();
  ray.dir_y = f.d.y();
  ray.dir_z = f.d.z();
  ray.tnear = f.shift == 0 ? tnear : std::ldexp(tnear, f.shift);
  ray.tfar = f.shift == 0 ? tfar : std::ldexp(tfar, f.shift);
  ray.time = 0.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(impl_->scene.get(), &context, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

namespace {
// Fills lanes [0, W) of an Embree packet (RTCRayW) with the first n rays in the BVH's frame
// (tfar 1 or infinity, times the ray's 2^shift) and marks them valid; the rest invalid.
template <int W, typename Packet>
void fill_packet(double scale, const Eigen::Vector3f* origin, const Eigen::Vector3f* direction,
                 int n, float tfar, Packet& rays, int* valid, int* shift) {
  for (int k = 0; k < W; ++k) {
    valid[k] = k < n ? -1 : 0;
    const FrameRay f = k < n ? to_bvh_frame(origin[k], direction[k], scale)
                             : FrameRay{Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitX(), 0};
    shift[k] = f.shift;
    rays.org_x[k] = f.o.x();
    rays.org_y[k] = f.o.y();
    rays.org_z[k] = f.o.z();
    rays.dir_x[k] = f.d.x();
    rays.dir_y[k] = f.d.y();
    rays.dir_z[k] = f.d.z();
    rays.tnear[k] = 0.0f;
    rays.tfar[k] = f.shift == 0 ? tfar : std::ldexp(tfar, f.shift);
    rays.time[k] = 0.0f;
    rays.mask[k] = 0xFFFFFFFFu;
    rays.id[k] = static_cast<unsigned>(k);
    rays.flags[k] = 0;
  }
}

template <int W, typename Packet, typename Trace>
void occluded_lanes(RTCScene scene, double scale, const Eigen::Vector3f* origin,
                    const Eigen::Vector3f* direction, int n, bool* hit, Trace trace) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(64) Packet rays;
  alignas(64) int valid[W];
  int shift[W];
  fill_packet<W>(scale, origin, direction, n, 1.0f, rays, valid, shift);
  trace(valid, scene, &context, &rays);
  for (int k = 0; k < n; ++k) hit[k] = rays.tfar[k] < 0.0f;
}

template <int W, typename Packet, typename Trace>
void intersect_lanes(RTCScene scene, double scale, const Eigen::Vector3f* origin,
                     const Eigen::Vector3f* direction, int n, RayHit* hit, Trace trace) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  alignas(64) Packet rh;
  alignas(64) int valid[W];
  int shift[W];
  fill_packet<W>(scale, origin, direction, n, std::numeric_limits<float>::infinity(), rh.ray, valid,
                 shift);
  for (int k = 0; k < W; ++k) {
    rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
  }
  trace(valid, scene, &context, &rh);
  for (int k = 0; k < n; ++k) {
    hit[k] = RayHit{};
    if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {
      hit[k].patch = static_cast<std::int32_t>(rh.hit.primID[k]);
      hit[k].t = std::ldexp(rh.ray.tfar[k], -shift[k]);
    }
  }
}
}  // namespace

void Bvh::intersect_packet(const Eigen::Vector3f* origin, const Eigen::Vector3f* direction, int n,
                           RayHit* hit) const {
  LAMBERT_CHECK(n <= kPacket, "intersect_packet: more rays than a packet holds");
  RTCScene scene = impl_->scene.get();
  if (n <= 1) {
    if (n == 1) hit[0] = intersect(origin[0], direction[0]);
  } else if (n <= 4) {
    intersect_lanes<4, RTCRayHit4>(scene, impl_->scale, origin, direction, n, hit, rtcIntersect4);
  } else if (n <= 8) {
    intersect_lanes<8, RTCRayHit8>(scene, impl_->scale, origin, direction, n, hit, rtcIntersect8);
  } else {
    intersect_lanes<16, RTCRayHit16>(scene, impl_->scale, origin, direction, n, hit,
                                     rtcIntersect16);
  }
}

void Bvh::occluded_packet(const Eigen::Vector3f* origin, const Eigen::Vector3f* direction, int n,
                          bool* hit) const {
  // The narrowest packet that holds the n rays (a wide packet's empty lanes cost as much as
  // full ones); a lone ray goes alone.
  LAMBERT_CHECK(n <= kPacket, "occluded_packet: more rays than a packet holds");
  RTCScene scene = impl_->scene.get();
  if (n <= 1) {
    if (n == 1) hit[0] = occluded(origin[0], direction[0], 0.0f, 1.0f);
  } else if (n <= 4) {
    occluded_lanes<4, RTCRay4>(scene, impl_->scale, origin, direction, n, hit, rtcOccluded4);
  } else if (n <= 8) {
    occluded_lanes<8, RTCRay8>(scene, impl_->scale, origin, direction, n, hit, rtcOccluded8);
  } else {
    occluded_lanes<16, RTCRay16>(scene, impl_->scale, origin, direction, n, hit, rtcOccluded16);
  }
}

namespace {
// Point-query callback: collects the primitive (= patch) ids Embree hands over.
bool collect_patch(RTCPointQueryFunctionArguments* args) {
  static_cast<std::vector<std::int32_t>*>(args->userPtr)
      ->push_back(static_cast<std::int32_t>(args->primID));
  return false;  // the query radius is unchanged
}
}  // namespace

void Bvh::patches_near(const Eigen::Vector3d& centre, double radius,
                       std::vector<std::int32_t>& out) const {
  const int e = impl_->exponent;
  RTCPointQuery query;
  query.x = static_cast<float>(std::ldexp(centre.x(), e));
  query.y = static_cast<float>(std::ldexp(centre.y(), e));
  query.z = static_cast<float>(std::ldexp(centre.z(), e));
  query.time = 0.0f;
  query.radius = static_cast<float>(
      std::ldexp(radius * (1.0 + 1e-6) + 1e-6 * centre.lpNorm<Eigen::Infinity>(), e));
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(impl_->scene.get(), &query, &context, collect_patch, &out);
}

RayHit Bvh::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float tnear,
                      float tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  const FrameRay f = to_bvh_frame(origin, direction, impl_->scale);
  RTCRayHit rh;
  rh.ray.org_x = f.o.x();
  rh.ray.org_y = f.o.y();
  rh.ray.org_z = f.o.z();
  rh.ray.dir_x = f.d.x();
  rh.ray.dir_y = f.d.y();
  rh.ray.dir_z = f.d.z();
  rh.ray.tnear = f.shift == 0 ? tnear : std::ldexp(tnear, f.shift);
  rh.ray.tfar = f.shift == 0 ? tfar : std::ldexp(tfar, f.shift);
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene.get(), &context, &rh);
  RayHit hit;
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    hit.patch = static_cast<std::int32_t>(rh.hit.primID);
    hit.t = std::ldexp(rh.ray.tfar, -f.shift);
  }
  return hit;
}

}  // namespace lambert
