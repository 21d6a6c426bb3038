#include "geometry/bvh.hpp"

#include <embree3/rtcore.h>

#include <atomic>
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

struct DeviceDeleter {
  void operator()(RTCDeviceTy* d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
  void operator()(RTCSceneTy* s) const { rtcReleaseScene(s); }
};

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

struct Bvh::Impl {
  std::shared_ptr<RTCDeviceTy> device;
  std::unique_ptr<RTCSceneTy, SceneDeleter> scene;  // released before the device
};

std::int64_t Bvh::builds() { return g_builds.load(); }

std::int64_t Bvh::devices() {
  DeviceRegistry& r = device_registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  return static_cast<std::int64_t>(r.devices.size());
}

Bvh::Bvh(const PatchMesh& mesh, int threads) : impl_(std::make_unique<Impl>()) {
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
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          mesh.vertices.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), mesh.patches.size()));
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    check_device(device, "rtcSetNewGeometryBuffer");
    throw Error("embree: cannot allocate geometry buffers");
  }
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    for (int d = 0; d < 3; ++d) vb[3 * v + d] = static_cast<float>(mesh.vertices[v][d]);
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
  RTCRay ray;
  ray.org_x = origin.x();
  ray.org_y = origin.y();
  ray.org_z = origin.z();
  ray.dir_x = direction.x();
  ray.dir_y = direction.y();
  ray.dir_z = direction.z();
  ray.tnear = tnear;
  ray.tfar = tfar;
  ray.time = 0.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(impl_->scene.get(), &context, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

namespace {
// Point-query callback: collects the primitive (= patch) ids Embree hands over.
bool collect_patch(RTCPointQueryFunctionArguments* args) {
  static_cast<std::vector<std::int32_t>*>(args->userPtr)->push_back(static_cast<std::int32_t>(args->primID));
  return false;  // the query radius is unchanged
}
}  // namespace

void Bvh::patches_near(const Eigen::Vector3d& centre, double radius,
                       std::vector<std::int32_t>& out) const {
  RTCPointQuery query;
  query.x = static_cast<float>(centre.x());
  query.y = static_cast<float>(centre.y());
  query.z = static_cast<float>(centre.z());
  query.time = 0.0f;
  query.radius = static_cast<float>(radius * (1.0 + 1e-6) + 1e-6 * centre.lpNorm<Eigen::Infinity>());
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(impl_->scene.get(), &query, &context, collect_patch, &out);
}

RayHit Bvh::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                      float tnear, float tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = origin.x();
  rh.ray.org_y = origin.y();
  rh.ray.org_z = origin.z();
  rh.ray.dir_x = direction.x();
  rh.ray.dir_y = direction.y();
  rh.ray.dir_z = direction.z();
  rh.ray.tnear = tnear;
  rh.ray.tfar = tfar;
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
    hit.t = rh.ray.tfar;
  }
  return hit;
}

}  // namespace lambert
