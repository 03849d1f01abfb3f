// The GPU half of the display: the film's mean goes to a float texture untouched (scene-linear); one
// pass runs OCIO's generated GLSL for the whole viewing pipeline into an 8-bit framebuffer at the
// image's resolution (so screenshots read back exactly what is shown); the window shows that
// framebuffer scaled into the image area. Nothing display-referred ever reaches the accumulation.
#pragma once

#include "color_pipeline.h"

#define GLFW_INCLUDE_GLCOREARB
#define GL_GLEXT_PROTOTYPES
#include <GLFW/glfw3.h>

#include <string>
#include <vector>

namespace candela {

// The part of the image shown: a zoomed view shows [u0, u1] x [v0, v1] of it (fractions, v down).
struct ViewWindow {
  float u0 = 0.0f, v0 = 0.0f, u1 = 1.0f, v1 = 1.0f;
};

class GlDisplay {
 public:
  GlDisplay();
  ~GlDisplay();
  GlDisplay(const GlDisplay&) = delete;
  GlDisplay& operator=(const GlDisplay&) = delete;

  // Uploads a scene-linear RGB image (interleaved floats, top row first). A smaller image than the
  // output (the preview pass) is upscaled with linear filtering.
  void uploadImage(int width, int height, const std::vector<float>& rgb);
  // Builds the OCIO shader for `settings`. On failure returns the reason and keeps the last program.
  std::string setPipeline(const ColorPipeline& pipeline, const DisplaySettings& settings);
  // Runs the display pass into the output framebuffer of `width` x `height` pixels.
  void renderOutput(int width, int height);
  // Draws the output into the window rectangle (pixels, origin bottom-left), preserving nothing else.
  // [from, to] selects a vertical strip of the window rectangle (fractions of its width) and draws
  // the matching strip of the view there: the wipe view.
  void blitToWindow(int x, int y, int w, int h, bool nearest, ViewWindow view = ViewWindow(), float from = 0.0f, float to = 1.0f) const;
  // The output as 8-bit RGB, top row first (what the window shows, before window scaling).
  std::vector<uint8_t> readOutput() const;
  // Red over the pixels at or past display white, blue over those at black (from the next renderOutput).
  void setClippingView(bool on) { clippingView_ = on; }
  int outputWidth() const { return outW_; }
  int outputHeight() const { return outH_; }

 private:
  struct LutTexture {
    GLuint id = 0;
    GLenum target = 0;
    std::string sampler;
  };
  void freeProgram();
  GLuint program_ = 0, vao_ = 0, vbo_ = 0, image_ = 0, fbo_ = 0, output_ = 0;
  std::vector<LutTexture> luts_;
  int outW_ = 0, outH_ = 0;
  bool clippingView_ = false;
};

}  // namespace candela
