#include "image_io.h"

#include "atomic_file.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace candela {

float srgbEncode(float x) {
  if (!(x > 0.0f)) return 0.0f;
  if (x >= 1.0f) return 1.0f;
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

namespace {
void writeExrFile(const std::string& path, const Image& image) {
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const auto& [k, v] : image.metadata) header.insert("candela/" + k, Imf::StringAttribute(v));
    const char* names[3] = {"R", "G", "B"};
    for (const char* n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
    const size_t pixels = static_cast<size_t>(image.width) * image.height;
    for (const auto& [name, values] : image.channels) {
      if (values.size() != pixels) throw std::runtime_error("channel " + name + " has " + std::to_string(values.size()) + " values, expected one per pixel");
      header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    }
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer fb;
    const size_t xs = 3 * sizeof(float), ys = xs * static_cast<size_t>(image.width);
    for (int c = 0; c < 3; ++c)
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(image.rgb.data()) + c), xs, ys));
    for (const auto& [name, values] : image.channels)
      fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(values.data())), sizeof(float),
                                 sizeof(float) * static_cast<size_t>(image.width)));
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": cannot write EXR (" + e.what() + ")");
  }
}

void writeDisplayPngFile(const std::string& path, const DisplayImage& image);
}  // namespace

void writeExr(const std::string& path, const Image& image) {
  writeAtomically(path, [&](const std::string& temporary) { writeExrFile(temporary, image); });
}

void writeDisplayPng(const std::string& path, const DisplayImage& image) {
  writeAtomically(path, [&](const std::string& temporary) { writeDisplayPngFile(temporary, image); });
}

Image readExr(const std::string& path) {
  Image image;
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    image.width = dw.max.x - dw.min.x + 1;
    image.height = dw.max.y - dw.min.y + 1;
    image.rgb.assign(3 * static_cast<size_t>(image.width) * image.height, 0.0f);
    Imf::FrameBuffer fb;
    const size_t xs = 3 * sizeof(float), ys = xs * static_cast<size_t>(image.width);
    const char* names[3] = {"R", "G", "B"};
    char* base = reinterpret_cast<char*>(image.rgb.data()) - (dw.min.x * xs + dw.min.y * ys);
    for (int c = 0; c < 3; ++c) fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys, 1, 1, 0.0));
    // Every further float channel (variance, spp) comes back too.
    const size_t pixels = static_cast<size_t>(image.width) * image.height;
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
      const std::string name = it.name();
      if (name == "R" || name == "G" || name == "B") continue;
      image.channels[name].assign(pixels, 0.0f);
    }
    for (auto& [name, values] : image.channels) {
      const size_t cxs = sizeof(float), cys = cxs * static_cast<size_t>(image.width);
      fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(values.data()) - (dw.min.x * cxs + dw.min.y * cys), cxs, cys, 1, 1, 0.0));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    for (auto it = file.header().begin(); it != file.header().end(); ++it) {
      const std::string name = it.name();
      if (name.rfind("candela/", 0) == 0)
        if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) image.metadata[name.substr(8)] = s->value();
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": cannot read EXR (" + e.what() + ")");
  }
  return image;
}

namespace {
void writeDisplayPngFile(const std::string& path, const DisplayImage& image) {
  if (image.rgb8.size() != 3 * static_cast<size_t>(image.width) * static_cast<size_t>(image.height))
    throw std::runtime_error(path + ": PNG pixel buffer does not match its size");
  std::unique_ptr<FILE, int (*)(FILE*)> fp(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!fp) throw std::runtime_error(path + ": cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error(path + ": PNG write failed");
  }
  png_init_io(png, fp.get());
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  std::vector<png_text> texts;
  std::vector<std::string> keys;
  for (const auto& [k, v] : image.metadata) keys.push_back("candela:" + k);
  size_t ki = 0;
  for (const auto& [k, v] : image.metadata) {
    png_text t{};
    t.compression = v.size() > 1000 ? PNG_TEXT_COMPRESSION_zTXt : PNG_TEXT_COMPRESSION_NONE;
    t.key = const_cast<char*>(keys[ki++].c_str());
    t.text = const_cast<char*>(v.c_str());
    t.text_length = v.size();
    texts.push_back(t);
  }
  if (!texts.empty()) png_set_text(png, info, texts.data(), static_cast<int>(texts.size()));
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, const_cast<png_byte*>(image.rgb8.data() + 3 * static_cast<size_t>(y) * image.width));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  // libpng does not check fwrite: a full disk shows here.
  if (std::fflush(fp.get()) != 0 || std::ferror(fp.get())) throw std::runtime_error(path + ": cannot write PNG (disk full?)");
}
}  // namespace

DisplayImage readDisplayPng(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> fp(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!fp) throw std::runtime_error(path + ": cannot open the PNG");
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw std::runtime_error(path + ": not a readable PNG");
  }
  png_init_io(png, fp.get());
  png_read_info(png, info);
  // Whatever the file holds, read 8-bit RGB.
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  png_set_palette_to_rgb(png);
  png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  DisplayImage image;
  image.width = static_cast<int>(png_get_image_width(png, info));
  image.height = static_cast<int>(png_get_image_height(png, info));
  image.rgb8.resize(3 * static_cast<size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y) png_read_row(png, image.rgb8.data() + 3 * static_cast<size_t>(y) * image.width, nullptr);
  png_read_end(png, info);
  png_textp texts = nullptr;
  int count = 0;
  png_get_text(png, info, &texts, &count);
  for (int i = 0; i < count; ++i) {
    const std::string key = texts[i].key;
    if (key.rfind("candela:", 0) == 0) image.metadata[key.substr(8)] = std::string(texts[i].text, texts[i].text_length);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

void writePng(const std::string& path, const Image& image, float exposureStops) {
  DisplayImage display;
  display.width = image.width;
  display.height = image.height;
  display.metadata = image.metadata;
  display.rgb8.resize(image.rgb.size());
  const float gain = std::exp2(exposureStops);
  for (size_t i = 0; i < image.rgb.size(); ++i)
    display.rgb8[i] = static_cast<uint8_t>(std::lround(255.0f * srgbEncode(image.rgb[i] * gain)));
  writeDisplayPng(path, display);
}

float autoExposureStops(const std::vector<float>& rgb) {
  float peak = 0.0f;
  std::vector<float> lum;
  lum.reserve(rgb.size() / 3);
  for (size_t i = 0; i + 2 < rgb.size(); i += 3) {
    const float l = 0.2126f * rgb[i] + 0.7152f * rgb[i + 1] + 0.0722f * rgb[i + 2];
    if (std::isfinite(l)) lum.push_back(l), peak = std::max(peak, l);
  }
  if (!(peak > 0.0f)) return 0.0f;
  double sumLog = 0.0;
  size_t n = 0;
  for (float l : lum)
    if (l > peak * 1e-6f) sumLog += std::log(static_cast<double>(l)), ++n;
  const double key = std::exp(sumLog / static_cast<double>(std::max<size_t>(1, n)));
  return std::clamp(static_cast<float>(std::log2(0.18 / key)), -16.0f, 16.0f);
}

bool isExrPath(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".exr";
}

void writeImage(const std::string& path, const Image& image) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  auto ends = [&](const char* ext) {
    const std::string e(ext);
    return path.size() >= e.size() && std::equal(e.rbegin(), e.rend(), path.rbegin(), [](char a, char b) { return a == std::tolower(b); });
  };
  if (ends(".exr")) return writeExr(path, image);
  if (ends(".png")) return writePng(path, image);
  throw std::runtime_error(path + ": expected an output ending in .exr or .png");
}

}  // namespace candela
