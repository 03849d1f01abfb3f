// Writes VDB files a hostile or careless pipeline could hand Candela, for the bad-input corpus
// (tests/hostile/corpus.py): extreme values, extreme transforms, stray far-away voxels, wrong grid
// types. Usage: hostile_vdb KIND OUT.vdb; `hostile_vdb list` prints the kinds.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <string>

namespace {

using openvdb::Coord;
using openvdb::FloatGrid;

// An empty grid named `name` with voxel size `voxel`.
template <class GridT = FloatGrid>
typename GridT::Ptr named(const std::string& name, double voxel) {
  auto grid = GridT::create(0);
  grid->setName(name);
  grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
  return grid;
}

// An 8^3 block of `value` at the origin, with voxel size `voxel`.
template <class GridT = FloatGrid>
typename GridT::Ptr block(typename GridT::ValueType value, double voxel = 0.05) {
  auto grid = named<GridT>("density", voxel);
  auto acc = grid->getAccessor();
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) acc.setValue(Coord(i, j, k), value);
  return grid;
}

void write(const std::string& out, openvdb::GridPtrVec grids) { openvdb::io::File(out).write(grids); }

}  // namespace

int main(int argc, char** argv) {
  openvdb::initialize();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  auto valued = [](float v) { return [v](const std::string& out) { write(out, {block(v)}); }; };
  auto scaled = [](double voxel) { return [voxel](const std::string& out) { write(out, {block(1.0f, voxel)}); }; };
  std::map<std::string, std::function<void(const std::string&)>> kinds = {
      {"ok", valued(1.0f)},
      {"value-1e30", valued(1e30f)},
      {"value-max-float", valued(std::numeric_limits<float>::max())},
      {"value-1e6", valued(1e6f)},
      {"value-nan", valued(nan)},
      {"value-inf", valued(inf)},
      {"value-negative", valued(-1.0f)},
      {"value-denormal", valued(1e-40f)},
      {"scale-1e30", scaled(1e30)},
      // OpenVDB itself refuses scales below about 1e-5 and singular matrices: files cannot hold them.
      {"scale-1e9", scaled(1e9)},
      {"translate-1e9",
       [](const std::string& out) {
         auto g = block(1.0f);
         openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
         m.preScale(openvdb::Vec3d(0.05));
         m.setTranslation(openvdb::Vec3d(1e9, 0, 0));
         g->setTransform(openvdb::math::Transform::createLinearTransform(m));
         write(out, {g});
       }},
      {"far-voxels-1e9",
       [](const std::string& out) {
         auto g = block(1.0f);
         g->tree().setValue(Coord(1000000000, 0, 0), 1.0f);
         g->tree().setValue(Coord(-1000000000, 0, 0), 1.0f);
         write(out, {g});
       }},
      {"far-voxels-1e6",
       [](const std::string& out) {
         auto g = block(1.0f);
         g->tree().setValue(Coord(1000000, 1000000, 1000000), 1.0f);
         g->tree().setValue(Coord(-1000000, -1000000, -1000000), 1.0f);
         write(out, {g});
       }},
      {"huge-tile",
       [](const std::string& out) {
         auto g = named("density", 0.01);
         g->tree().addTile(3, Coord(0), 1.0f, true);  // a 4096^3 constant tile
         write(out, {g});
       }},
      {"empty",
       [](const std::string& out) {
         auto g = FloatGrid::create(0.0f);
         g->setName("density");
         write(out, {g});
       }},
      {"no-grids", [](const std::string& out) { write(out, {}); }},
      {"wrong-name",
       [](const std::string& out) {
         auto g = block(1.0f);
         g->setName("smoke");
         write(out, {g});
       }},
      {"vec3-density",
       [](const std::string& out) {
         auto g = openvdb::Vec3SGrid::create();
         g->setName("density");
         g->tree().setValue(Coord(0), openvdb::Vec3s(1, 1, 1));
         write(out, {g});
       }},
      {"int-density",
       [](const std::string& out) {
         auto g = openvdb::Int32Grid::create(0);
         g->setName("density");
         g->tree().setValue(Coord(0), 5);
         write(out, {g});
       }},
      // 64-bit precision (a Houdini option): read as float.
      {"double-density",
       [](const std::string& out) {
         write(out, {block<openvdb::DoubleGrid>(1.0)});
       }},
      // A double beyond float's range: infinite once read as float, so set to 0 and counted.
      {"double-1e300",
       [](const std::string& out) {
         auto g = named<openvdb::DoubleGrid>("density", 0.05);
         g->tree().setValue(Coord(0), 1.0);
         g->tree().setValue(Coord(1, 0, 0), 1e300);
         write(out, {g});
       }},
      {"bool-density",
       [](const std::string& out) {
         auto g = openvdb::BoolGrid::create(false);
         g->setName("density");
         g->tree().setValue(Coord(0), true);
         write(out, {g});
       }},
      {"frustum",
       [](const std::string& out) {
         auto g = block(1.0f);
         const openvdb::BBoxd box(openvdb::Vec3d(0), openvdb::Vec3d(8));
         g->setTransform(openvdb::math::Transform::createFrustumTransform(box, 0.5, 2.0, 0.1));
         write(out, {g});
       }},
      {"background-1",
       [](const std::string& out) {
         // A non-zero background: the whole infinite domain would be dense.
         auto g = FloatGrid::create(1.0f);
         g->setName("density");
         g->tree().setValue(Coord(0), 2.0f);
         write(out, {g});
       }},
      // A signed distance field (a collision object, a converted mesh) named as the density: its
      // class says level set, so it renders as the fog volume it bounds, with a warning.
      {"level-set",
       [](const std::string& out) {
         auto g = openvdb::tools::createLevelSetSphere<FloatGrid>(0.2f, openvdb::Vec3f(0.2f), 0.02f);
         g->setName("density");
         write(out, {g});
       }},
      // The same distances with the class left unknown: a positive background, refused with a hint.
      {"level-set-unmarked",
       [](const std::string& out) {
         auto g = openvdb::tools::createLevelSetSphere<FloatGrid>(0.2f, openvdb::Vec3f(0.2f), 0.02f);
         g->setName("density");
         g->setGridClass(openvdb::GRID_UNKNOWN);
         write(out, {g});
       }},
      // A level set whose narrow band has no width (background 0): nothing to say where inside ends.
      {"level-set-background-0",
       [](const std::string& out) {
         auto g = block(1.0f);
         g->setGridClass(openvdb::GRID_LEVEL_SET);
         write(out, {g});
       }},
      // Emission per unit length reaching past the density (the renderer tracks the density's box):
      // a flame grid of the same voxels, and a temperature grid of voxels twice as large.
      {"flame-beyond-density",
       [](const std::string& out) {
         auto flame = named("flame", 0.05);
         flame->tree().setValue(Coord(20, 2, 2), 1.0f);
         flame->tree().setValue(Coord(2, 2, 2), 1.0f);
         write(out, {block(1.0f), flame});
       }},
      {"temperature-beyond-density",
       [](const std::string& out) {
         auto temperature = named("temperature", 0.1);
         for (int i = 0; i < 8; ++i) temperature->tree().setValue(Coord(i, 1, 1), 1.0f);  // 0.1 to 0.8 in x; the density ends at 0.4
         write(out, {block(1.0f), temperature});
       }},
      {"duplicate-names",
       [](const std::string& out) {
         auto a = block(1.0f), b = block(2.0f);
         write(out, {a, b});
       }},
  };
  if (argc == 2 && std::string(argv[1]) == "list") {
    for (const auto& [name, fn] : kinds) std::printf("%s\n", name.c_str());
    return 0;
  }
  if (argc != 3 || !kinds.count(argv[1])) {
    std::fprintf(stderr, "usage: hostile_vdb KIND OUT.vdb (hostile_vdb list)\n");
    return 2;
  }
  try {
    kinds[argv[1]](argv[2]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hostile_vdb: %s: %s\n", argv[1], e.what());
    return 1;
  }
  return 0;
}
