#include "gl_display.h"

#include <stdexcept>

namespace candela {

namespace {

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec2 position;
out vec2 uv;
void main() {
  uv = position * 0.5 + 0.5;
  gl_Position = vec4(position, 0.0, 1.0);
}
)";

// The compile or link log of a shader or program.
std::string infoLog(GLuint object, bool program) {
  char buffer[4096] = {};
  if (program)
    glGetProgramInfoLog(object, sizeof(buffer), nullptr, buffer);
  else
    glGetShaderInfoLog(object, sizeof(buffer), nullptr, buffer);
  return buffer;
}

GLuint compile(GLenum type, const std::string& source, std::string& log) {
  GLuint shader = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    log = infoLog(shader, false);
    glDeleteShader(shader);
    return 0;
  }
  return shader;
}

}  // namespace

GlDisplay::GlDisplay() {
  const float quad[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, sizeof(quad), quad, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindVertexArray(0);
  glGenTextures(1, &image_);
  glBindTexture(GL_TEXTURE_2D, image_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glGenFramebuffers(1, &fbo_);
  glGenTextures(1, &output_);
}

GlDisplay::~GlDisplay() {
  freeProgram();
  glDeleteTextures(1, &image_);
  glDeleteTextures(1, &output_);
  glDeleteFramebuffers(1, &fbo_);
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
}

void GlDisplay::freeProgram() {
  if (program_) glDeleteProgram(program_);
  program_ = 0;
  for (auto& t : luts_) glDeleteTextures(1, &t.id);
  luts_.clear();
}

void GlDisplay::uploadImage(int width, int height, const std::vector<float>& rgb) {
  // Row 0 of the texture is the image's top row; the display pass keeps that order (see blit).
  glBindTexture(GL_TEXTURE_2D, image_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, width, height, 0, GL_RGB, GL_FLOAT, rgb.data());
}

std::string GlDisplay::setPipeline(const ColorPipeline& pipeline, const DisplaySettings& settings) {
  OCIO::GpuShaderDescRcPtr desc;
  try {
    desc = OCIO::GpuShaderDesc::CreateShaderDesc();
    desc->setLanguage(OCIO::GPU_LANGUAGE_GLSL_4_0);  // compiles under #version 330 core
    desc->setFunctionName("OCIODisplay");
    desc->setResourcePrefix("ocio_");
    pipeline.processor(settings)->getDefaultGPUProcessor()->extractGpuShaderInfo(desc);
  } catch (const std::exception& e) {
    return std::string("OCIO: ") + e.what();
  }
  const std::string fragment = std::string("#version 330 core\n") + desc->getShaderText() + R"(
in vec2 uv;
out vec4 fragColor;
uniform sampler2D sceneLinear;
uniform int clippingView;
void main() {
  fragColor = OCIODisplay(vec4(texture(sceneLinear, uv).rgb, 1.0));
  // The clipping view: display values the screen cannot show, in false colour (red: a channel at
  // or past white; blue: every channel at black).
  if (clippingView != 0) {
    if (any(greaterThanEqual(fragColor.rgb, vec3(1.0)))) fragColor.rgb = vec3(1.0, 0.0, 0.0);
    else if (all(lessThanEqual(fragColor.rgb, vec3(0.0)))) fragColor.rgb = vec3(0.0, 0.25, 1.0);
  }
}
)";
  std::string log;
  GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader, log);
  GLuint fs = vs ? compile(GL_FRAGMENT_SHADER, fragment, log) : 0;
  if (!vs || !fs) {
    if (vs) glDeleteShader(vs);
    return "display shader failed to compile: " + log;
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = infoLog(program, true);
    glDeleteProgram(program);
    return "display shader failed to link: " + log;
  }
  freeProgram();
  program_ = program;

  // OCIO's LUTs (none for the shipped config's views; a user config may have some).
  auto filter = [](OCIO::Interpolation i) { return i == OCIO::INTERP_NEAREST ? GL_NEAREST : GL_LINEAR; };
  for (unsigned i = 0; i < desc->getNum3DTextures(); ++i) {
    const char *name = nullptr, *sampler = nullptr;
    unsigned edge = 0;
    OCIO::Interpolation interp;
    desc->get3DTexture(i, name, sampler, edge, interp);
    const float* values = nullptr;
    desc->get3DTextureValues(i, values);
    LutTexture t{0, GL_TEXTURE_3D, sampler};
    glGenTextures(1, &t.id);
    glBindTexture(GL_TEXTURE_3D, t.id);
    glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, filter(interp));
    glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, filter(interp));
    for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R}) glTexParameteri(GL_TEXTURE_3D, w, GL_CLAMP_TO_EDGE);
    glTexImage3D(GL_TEXTURE_3D, 0, GL_RGB32F, edge, edge, edge, 0, GL_RGB, GL_FLOAT, values);
    luts_.push_back(t);
  }
  for (unsigned i = 0; i < desc->getNumTextures(); ++i) {
    const char *name = nullptr, *sampler = nullptr;
    unsigned width = 0, height = 0;
    OCIO::GpuShaderDesc::TextureType channel;
    OCIO::Interpolation interp;
    desc->getTexture(i, name, sampler, width, height, channel, interp);
    const float* values = nullptr;
    desc->getTextureValues(i, values);
    const bool red = channel == OCIO::GpuShaderDesc::TEXTURE_RED_CHANNEL;
    LutTexture t{0, height > 1 ? GLenum(GL_TEXTURE_2D) : GLenum(GL_TEXTURE_1D), sampler};
    glGenTextures(1, &t.id);
    glBindTexture(t.target, t.id);
    glTexParameteri(t.target, GL_TEXTURE_MIN_FILTER, filter(interp));
    glTexParameteri(t.target, GL_TEXTURE_MAG_FILTER, filter(interp));
    glTexParameteri(t.target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(t.target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    if (height > 1)
      glTexImage2D(GL_TEXTURE_2D, 0, red ? GL_R32F : GL_RGB32F, width, height, 0, red ? GL_RED : GL_RGB, GL_FLOAT, values);
    else
      glTexImage1D(GL_TEXTURE_1D, 0, red ? GL_R32F : GL_RGB32F, width, 0, red ? GL_RED : GL_RGB, GL_FLOAT, values);
    luts_.push_back(t);
  }
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "sceneLinear"), 0);
  for (size_t i = 0; i < luts_.size(); ++i) glUniform1i(glGetUniformLocation(program_, luts_[i].sampler.c_str()), static_cast<GLint>(i + 1));
  // Dynamic properties become uniforms; our processors are rebuilt on every change, so they are
  // constants here, set once.
  for (unsigned i = 0; i < desc->getNumUniforms(); ++i) {
    OCIO::GpuShaderDesc::UniformData data;
    const char* name = desc->getUniform(i, data);
    const GLint loc = glGetUniformLocation(program_, name);
    if (data.m_type == OCIO::UNIFORM_DOUBLE && data.m_getDouble) glUniform1f(loc, static_cast<float>(data.m_getDouble()));
    if (data.m_type == OCIO::UNIFORM_BOOL && data.m_getBool) glUniform1i(loc, data.m_getBool() ? 1 : 0);
    if (data.m_type == OCIO::UNIFORM_FLOAT3 && data.m_getFloat3) glUniform3fv(loc, 1, data.m_getFloat3().data());
  }
  glUseProgram(0);
  return {};
}

void GlDisplay::renderOutput(int width, int height) {
  if (!program_) return;
  if (width != outW_ || height != outH_) {
    outW_ = width;
    outH_ = height;
    glBindTexture(GL_TEXTURE_2D, output_);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, output_, 0);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width, height);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "clippingView"), clippingView_ ? 1 : 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, image_);
  for (size_t i = 0; i < luts_.size(); ++i) {
    glActiveTexture(GL_TEXTURE1 + static_cast<GLenum>(i));
    glBindTexture(luts_[i].target, luts_[i].id);
  }
  glActiveTexture(GL_TEXTURE0);
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glBindVertexArray(0);
  glUseProgram(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void GlDisplay::blitToWindow(int x, int y, int w, int h, bool nearest, ViewWindow view, float from, float to) const {
  if (!outW_) return;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const int sx0 = static_cast<int>(lerp(view.u0, view.u1, from) * outW_ + 0.5f), sx1 = static_cast<int>(lerp(view.u0, view.u1, to) * outW_ + 0.5f);
  const int sy0 = static_cast<int>(view.v0 * outH_ + 0.5f), sy1 = static_cast<int>(view.v1 * outH_ + 0.5f);
  const int dx0 = x + static_cast<int>(from * w + 0.5f), dx1 = x + static_cast<int>(to * w + 0.5f);
  // The output's row 0 is the image's top row: flip it onto the window (GL's origin is bottom-left).
  glBlitFramebuffer(sx0, sy0, sx1, sy1, dx0, y + h, dx1, y, GL_COLOR_BUFFER_BIT, nearest ? GL_NEAREST : GL_LINEAR);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
}

std::vector<uint8_t> GlDisplay::readOutput() const {
  std::vector<uint8_t> rgb(3 * static_cast<size_t>(outW_) * outH_);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, outW_, outH_, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());  // row 0 first: the image's top
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  return rgb;
}

}  // namespace candela
