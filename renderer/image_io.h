// Image files: scene-linear EXR (float RGB) and display PNG (plain sRGB transfer for now), both
// carrying string metadata (scene path, settings JSON, spp, time).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace candela {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // interleaved, scene-linear
  std::map<std::string, std::string> metadata;
  // Further per-pixel float channels written to the EXR beside R, G, B, by their EXR names
  // ("variance.R", "spp": a compositor shows "variance" as a layer). One value per pixel each.
  std::map<std::string, std::vector<float>> channels;
};

// An 8-bit display-referred image (what a display transform produced), as the viewer's screenshots hold.
struct DisplayImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb8;  // interleaved, top row first
  std::map<std::string, std::string> metadata;
};

void writeExr(const std::string& path, const Image& image);
bool isExrPath(const std::string& path);  // ends in .exr, any case
Image readExr(const std::string& path);
// Applies exposure (stops) and the sRGB transfer function, clamps, writes 8-bit RGB.
void writePng(const std::string& path, const Image& image, float exposureStops = 0.0f);
// Writes / reads display-referred 8-bit RGB PNGs; metadata travels as "candela:KEY" text chunks.
void writeDisplayPng(const std::string& path, const DisplayImage& image);
DisplayImage readDisplayPng(const std::string& path);
// Writes by extension: .exr or .png. Throws std::runtime_error on other extensions or I/O errors.
void writeImage(const std::string& path, const Image& image);

float srgbEncode(float linear);

// Exposure in stops that brings the image's log-average luminance to middle grey (0.18), over the
// pixels brighter than a millionth of the brightest (a black background does not drag it up);
// clamped to +-16 stops. 0 for an all-black image.
float autoExposureStops(const std::vector<float>& rgb);

}  // namespace candela
