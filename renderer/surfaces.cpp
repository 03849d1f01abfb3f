#include "surfaces.h"

#include "work.h"

#include <embree3/rtcore.h>

#include <stdexcept>

namespace candela {

namespace {
constexpr int kCylinderSegments = 96;
}

struct Surfaces::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<int> surfaceOfGeometry;
};

namespace {

void addMesh(RTCDevice device, RTCScene scene, const std::vector<Vec3>& vertices, const std::vector<glm::uvec3>& triangles,
             unsigned id) {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.size()));
  for (size_t i = 0; i < vertices.size(); ++i) {
    v[3 * i] = vertices[i].x;
    v[3 * i + 1] = vertices[i].y;
    v[3 * i + 2] = vertices[i].z;
  }
  auto* idx = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles.size()));
  for (size_t i = 0; i < triangles.size(); ++i) {
    idx[3 * i] = triangles[i].x;
    idx[3 * i + 1] = triangles[i].y;
    idx[3 * i + 2] = triangles[i].z;
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, id);
  rtcReleaseGeometry(geom);
}

}  // namespace

Surfaces::Surfaces(const std::vector<SurfaceDesc>& surfaces) : impl_(std::make_unique<Impl>()), descs_(surfaces) {
  if (descs_.empty()) return;
  // No "threads=N" here: Embree would install a process-wide TBB limit and serialise our tiles.
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  for (size_t s = 0; s < descs_.size(); ++s) {
    const SurfaceDesc& d = descs_[s];
    const unsigned id = static_cast<unsigned>(s);
    std::vector<Vec3> v;
    std::vector<glm::uvec3> tri;
    switch (d.type) {
      case SurfaceType::Plane:
        v = {{-d.size, d.height, -d.size}, {d.size, d.height, -d.size}, {d.size, d.height, d.size}, {-d.size, d.height, d.size}};
        tri = {{0, 2, 1}, {0, 3, 2}};
        addMesh(impl_->device, impl_->scene, v, tri, id);
        break;
      case SurfaceType::Box: {
        for (int c = 0; c < 8; ++c) v.push_back(boxCorner(d.min, d.max, c));
        tri = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
               {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
        addMesh(impl_->device, impl_->scene, v, tri, id);
        break;
      }
      case SurfaceType::Cylinder: {
        // Side quads first (2 triangles per segment), then the two caps as fans.
        const unsigned n = kCylinderSegments;
        for (unsigned i = 0; i < n; ++i) {
          const float a = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(n);
          const Vec3 r(d.radius * std::cos(a), 0.0f, d.radius * std::sin(a));
          v.push_back(d.center + r);
          v.push_back(d.center + r + Vec3(0.0f, d.length, 0.0f));
        }
        const unsigned bottom = static_cast<unsigned>(v.size());
        v.push_back(d.center);
        v.push_back(d.center + Vec3(0.0f, d.length, 0.0f));
        for (unsigned i = 0; i < n; ++i) {
          const unsigned j = (i + 1) % n;
          tri.emplace_back(2 * i, 2 * i + 1, 2 * j);
          tri.emplace_back(2 * j, 2 * i + 1, 2 * j + 1);
        }
        for (unsigned i = 0; i < n; ++i) {
          const unsigned j = (i + 1) % n;
          tri.emplace_back(bottom, 2 * i, 2 * j);
          tri.emplace_back(bottom + 1, 2 * j + 1, 2 * i + 1);
        }
        addMesh(impl_->device, impl_->scene, v, tri, id);
        break;
      }
      case SurfaceType::Sphere: {
        RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        auto* p = static_cast<float*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
        p[0] = d.center.x;
        p[1] = d.center.y;
        p[2] = d.center.z;
        p[3] = d.radius;
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(impl_->scene, geom, id);
        rtcReleaseGeometry(geom);
        break;
      }
    }
  }
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(impl_->scene);
}

Surfaces::~Surfaces() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

SurfaceHit Surfaces::intersect(const Ray& ray, float tMax) const {
  SurfaceHit out;
  if (!impl_->scene) return out;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = ray.origin.x;
  rh.ray.org_y = ray.origin.y;
  rh.ray.org_z = ray.origin.z;
  rh.ray.dir_x = ray.direction.x;
  rh.ray.dir_y = ray.direction.y;
  rh.ray.dir_z = ray.direction.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = tMax;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.flags = 0;
  rh.ray.time = 0.0f;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  ++threadWork().rays;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
  const SurfaceDesc& d = descs_[rh.hit.geomID];
  out.t = rh.ray.tfar;
  out.albedo = d.albedo;
  Vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  const Vec3 p = ray.at(out.t);
  if (d.type == SurfaceType::Sphere) n = p - d.center;
  if (d.type == SurfaceType::Cylinder && rh.hit.primID < 2u * kCylinderSegments) n = Vec3(p.x - d.center.x, 0.0f, p.z - d.center.z);
  out.normal = glm::normalize(n);
  return out;
}

bool Surfaces::occluded(const Ray& ray, float tMax) const {
  if (!impl_->scene) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r;
  r.org_x = ray.origin.x;
  r.org_y = ray.origin.y;
  r.org_z = ray.origin.z;
  r.dir_x = ray.direction.x;
  r.dir_y = ray.direction.y;
  r.dir_z = ray.direction.z;
  r.tnear = 0.0f;
  r.tfar = tMax;
  r.mask = 0xFFFFFFFFu;
  r.flags = 0;
  r.time = 0.0f;
  ++threadWork().rays;
  rtcOccluded1(impl_->scene, &context, &r);
  return r.tfar < 0.0f;
}

}  // namespace candela
