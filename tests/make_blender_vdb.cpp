// Writes a VDB shaped like a Blender Mantaflow bake for the GUI and CLI tests: Z-up (a plume tall
// along Z), grids density, flame, heat and a vec3 velocity, and Blender's metadata key.
//   make_blender_vdb OUT.vdb
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_blender_vdb OUT.vdb\n");
    return 2;
  }
  openvdb::initialize();
  auto density = openvdb::FloatGrid::create(0.0f), flame = openvdb::FloatGrid::create(0.0f), heat = openvdb::FloatGrid::create(0.0f);
  auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  density->setName("density"), flame->setName("flame"), heat->setName("heat"), velocity->setName("velocity");
  auto transform = openvdb::math::Transform::createLinearTransform(0.04);
  for (auto g : {openvdb::GridBase::Ptr(density), openvdb::GridBase::Ptr(flame), openvdb::GridBase::Ptr(heat), openvdb::GridBase::Ptr(velocity)})
    g->setTransform(transform);
  auto d = density->getAccessor(), f = flame->getAccessor(), h = heat->getAccessor();
  auto v = velocity->getAccessor();
  // A cone of smoke 48 voxels tall along Z with flame at its base.
  for (int z = 0; z < 48; ++z)
    for (int y = -16; y < 16; ++y)
      for (int x = -16; x < 16; ++x) {
        const float r = std::sqrt(float(x * x + y * y)), radius = 4.0f + 10.0f * z / 48.0f;
        if (r > radius) continue;
        const openvdb::Coord c(x, y, z);
        d.setValue(c, 3.0f * (1.0f - r / radius));
        if (z < 10) f.setValue(c, 1.0f - z / 10.0f), h.setValue(c, 1.0f);
        v.setValue(c, openvdb::Vec3s(0.0f, 0.0f, 1.0f));
      }
  openvdb::MetaMap meta;
  meta.insertMeta("blender/smoke/active_fields", openvdb::Int32Metadata(5));
  openvdb::io::File file(argv[1]);
  file.write({density, flame, heat, velocity}, meta);
  file.close();
  std::printf("wrote %s\n", argv[1]);
  return 0;
}
