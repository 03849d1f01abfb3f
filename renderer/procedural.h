// Built-in procedural volumes (docs/method.md s.0 scenes): torch flame, mist, cloud, smoke plume and the
// closed-form test shapes. Deterministic for a given description; written as real .vdb files.
#pragma once

#include "scene_desc.h"

#include <string>

namespace candela {

// Where generated volumes and reference renders are cached: $CANDELA_CACHE_DIR, else
// $XDG_CACHE_HOME/candela, else $HOME/.cache/candela, else /tmp/candela-cache.
std::string cacheDirectory();

// The peak density (GeneratorDesc::value) `candela-cli generate` gives a shape, so that the .vdb it
// writes, opened on its own, reads as the shipped scene that uses the shape: the sigma_t_scale that
// scene gives it (cloud 12, torch 6, plume 1.5, mist 0.1; 1 for constant and ramp).
float standaloneDensity(const std::string& type);

// Writes the generator's grids ("density", and "temperature" for torch, plume and any constant or
// ramp with a temperature) to `path` as an OpenVDB file.
void writeGeneratedVolume(const GeneratorDesc& gen, const std::string& path);

// The cached .vdb for a generator, generating it first when it is not cached yet.
std::string cachedGeneratedVolume(const GeneratorDesc& gen);

}  // namespace candela
