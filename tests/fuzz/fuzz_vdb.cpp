// libFuzzer target: the VDB loader (loadVdbGrids) on arbitrary bytes, asking for a density and a
// temperature grid as a blackbody volume does, and opening the bytes as a bare VDB does (the grid
// list, its metadata and bounding boxes: sceneFromVdb) and reading a vec3 colour grid. Any outcome but a result or an InputError is
// a finding.
#include "vdb_import.h"
#include "vdb_io.h"

#include "fields.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // OpenVDB reads files only: one scratch file per process, removed when the process exits normally.
  struct ScratchFile {
    std::string path;
    ~ScratchFile() { std::remove(path.c_str()); }
  };
  static const ScratchFile scratch{"/tmp/candela-fuzz-vdb-" + std::to_string(::getpid()) + ".vdb"};
  const std::string& path = scratch.path;
  if (FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  } else {
    return 0;
  }
  try {
    (void)candela::loadVdbGrids(path, {"density", "temperature"}, "volumes.0.file");
  } catch (const candela::InputError&) {
  }
  try {
    (void)candela::sceneFromVdb(path);
  } catch (const candela::InputError&) {
  }
  try {
    (void)candela::loadVdbVectorGrid(path, "Cd", "volumes.0.color_grid");
  } catch (const candela::InputError&) {
  }
  return 0;
}
