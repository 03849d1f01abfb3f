// The OpenColorIO display pipeline, without GL: config loading with fallback, the menus' contents, and
// one processor per DisplaySettings built with OCIO's LegacyViewingPipeline, so the order is OCIO's:
// exposure (linearCC, scene-linear) -> channel view -> look -> display/view -> gamma (displayCC).
// The viewer runs that processor on the GPU (gl_display.cpp); tests and batch tools run it on the CPU.
#pragma once

#include "view_settings.h"

#include <OpenColorIO/OpenColorIO.h>

#include <memory>
#include <string>
#include <vector>

namespace candela {

namespace OCIO = OCIO_NAMESPACE;

class ColorPipeline {
 public:
  // Loads `path`; when empty, $OCIO, else the shipped config. A config that fails to load or
  // validate falls back to the shipped one; the reason is kept in message().
  static ColorPipeline load(const std::string& path = "");
  static std::string shippedConfigPath();

  const std::string& configPath() const { return configPath_; }
  // Empty when the requested config loaded; otherwise why it fell back.
  const std::string& message() const { return message_; }
  OCIO::ConstConfigRcPtr config() const { return config_; }

  std::vector<std::string> displays() const;
  std::vector<std::string> views(const std::string& display) const;
  std::vector<std::string> looks() const;
  // Settings with empty or unknown display/view/look replaced by the config's defaults.
  DisplaySettings resolve(const DisplaySettings& settings) const;

  // The whole viewing pipeline as one processor (resolve() is applied first).
  OCIO::ConstProcessorRcPtr processor(const DisplaySettings& settings) const;
  // Applies it on the CPU to interleaved RGB floats.
  void applyCpu(const DisplaySettings& settings, std::vector<float>& rgb) const;

 private:
  OCIO::ConstConfigRcPtr config_;
  std::string configPath_, message_;
};

// 8-bit quantisation of display-referred values, as the GL framebuffer stores them.
inline uint8_t toDisplayByte(float v) {
  v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
  return static_cast<uint8_t>(v * 255.0f + 0.5f);
}

}  // namespace candela
