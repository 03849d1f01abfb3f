// The OCIO display pipeline (ui/color_pipeline): the shipped config, the order of the viewing
// pipeline checked against separately built CPU processors, channel views and config fallback.
#include "color_pipeline.h"
#include "image_io.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <random>

namespace candela {
namespace {

std::vector<float> randomColors(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> rgb(3 * static_cast<size_t>(n));
  // Scene-linear values over about 10 stops, with saturated colours among them.
  for (auto& v : rgb) v = 0.002f * std::exp2(10.0f * u(rng));
  return rgb;
}

std::vector<float> applied(const ColorPipeline& p, const DisplaySettings& s, std::vector<float> rgb) {
  p.applyCpu(s, rgb);
  return rgb;
}

double maxDifference(const std::vector<float>& a, const std::vector<float>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(static_cast<double>(a[i]) - b[i]));
  return m;
}

TEST(ColorPipeline, ShippedConfigHasTheDocumentedViewsAndLooks) {
  const ColorPipeline p = ColorPipeline::load(ColorPipeline::shippedConfigPath());
  EXPECT_TRUE(p.message().empty()) << p.message();
  const auto displays = p.displays();
  ASSERT_FALSE(displays.empty());
  EXPECT_EQ(displays.front(), "sRGB");
  const auto views = p.views("sRGB");
  EXPECT_NE(std::find(views.begin(), views.end(), "ACES 1.0 - SDR Video"), views.end());
  EXPECT_NE(std::find(views.begin(), views.end(), "Un-tone-mapped"), views.end());
  EXPECT_NE(std::find(views.begin(), views.end(), "Raw"), views.end());
  EXPECT_EQ(p.looks().size(), 2u);
  const DisplaySettings resolved = p.resolve(DisplaySettings{});
  EXPECT_EQ(resolved.display, "sRGB");
  EXPECT_EQ(resolved.view, "ACES 1.0 - SDR Video");
}

// Closed form: linear Rec.709 through the un-tone-mapped sRGB view is the sRGB encoding, and the raw
// view passes data through.
TEST(ColorPipeline, UntonemappedViewIsTheSrgbEncodingAndRawIsIdentity) {
  const ColorPipeline p = ColorPipeline::load(ColorPipeline::shippedConfigPath());
  const std::vector<float> in = {0.0f, 0.0f, 0.0f, 0.18f, 0.18f, 0.18f, 0.5f, 0.2f, 0.05f, 1.0f, 1.0f, 1.0f};
  DisplaySettings s;
  s.display = "sRGB";
  s.view = "Un-tone-mapped";
  const auto out = applied(p, s, in);
  for (size_t i = 0; i < in.size(); ++i) EXPECT_NEAR(out[i], srgbEncode(in[i]), 2e-3) << i;
  s.view = "Raw";
  EXPECT_LT(maxDifference(applied(p, s, in), in), 1e-6);
}

// The order of OCIO's viewing pipeline: exposure on scene-linear values before the look and the view,
// gamma on display values after them. Built here from separate processors and compared.
TEST(ColorPipeline, ExposureBeforeLookAndViewGammaAfter) {
  const ColorPipeline p = ColorPipeline::load(ColorPipeline::shippedConfigPath());
  const auto in = randomColors(4096, 7);
  for (const char* view : {"ACES 1.0 - SDR Video", "Un-tone-mapped"})
    for (const char* look : {"", "Contrast", "Warm"}) {
      DisplaySettings full;
      full.display = "sRGB";
      full.view = view;
      full.look = look;
      full.exposure = 1.5f;
      full.gamma = 1.4f;
      DisplaySettings viewOnly = full;
      viewOnly.exposure = 0.0f;
      viewOnly.gamma = 1.0f;

      std::vector<float> expected = in;
      for (auto& v : expected) v *= std::exp2(1.5f);            // exposure, scene-linear
      expected = applied(p, viewOnly, expected);                 // look + display/view
      for (auto& v : expected) v = std::pow(std::max(v, 0.0f), 1.0f / 1.4f);  // gamma, display-referred
      const auto got = applied(p, full, in);
      EXPECT_LT(maxDifference(got, expected), 1e-4) << view << " look " << look;

      // The order matters for these views: exposure after the view would differ visibly.
      std::vector<float> wrongOrder = applied(p, viewOnly, in);
      for (auto& v : wrongOrder) v = std::pow(std::max(v * std::exp2(1.5f), 0.0f), 1.0f / 1.4f);
      EXPECT_GT(maxDifference(got, wrongOrder), 0.02) << view << " look " << look;
    }
}

TEST(ColorPipeline, LookChangesTheImageAndDefaultsToNone) {
  const ColorPipeline p = ColorPipeline::load(ColorPipeline::shippedConfigPath());
  const auto in = randomColors(256, 3);
  DisplaySettings none, warm;
  warm.look = "Warm";
  const auto a = applied(p, none, in), b = applied(p, warm, in);
  EXPECT_GT(maxDifference(a, b), 0.01);
  // Warm raises red relative to blue on a grey input.
  const auto grey = applied(p, warm, {0.18f, 0.18f, 0.18f});
  EXPECT_GT(grey[0], grey[2] + 0.02f);
  DisplaySettings unknown;
  unknown.look = "no such look";
  EXPECT_TRUE(p.resolve(unknown).look.empty());
}

TEST(ColorPipeline, ChannelViewsShowOneChannelAsGrey) {
  const ColorPipeline p = ColorPipeline::load(ColorPipeline::shippedConfigPath());
  const std::vector<float> in = {0.6f, 0.1f, 0.02f};
  DisplaySettings s;
  s.view = "Un-tone-mapped";
  for (auto [channel, value] : {std::pair{ChannelView::Red, 0.6f}, std::pair{ChannelView::Green, 0.1f}, std::pair{ChannelView::Blue, 0.02f},
                                std::pair{ChannelView::Luminance, 0.2126f * 0.6f + 0.7152f * 0.1f + 0.0722f * 0.02f}}) {
    s.channel = channel;
    const auto out = applied(p, s, in);
    EXPECT_NEAR(out[0], srgbEncode(value), 3e-3) << enumName(channel);
    EXPECT_NEAR(out[1], out[0], 2e-3);
    EXPECT_NEAR(out[2], out[0], 2e-3);
  }
}

TEST(ColorPipeline, BrokenConfigFallsBackToTheShippedOneWithAMessage) {
  const std::string bad = testing::TempDir() + "/broken.ocio";
  std::ofstream(bad) << "ocio_profile_version: 2\nroles: [this is not a config\n";
  const ColorPipeline p = ColorPipeline::load(bad);
  EXPECT_EQ(p.configPath(), ColorPipeline::shippedConfigPath());
  EXPECT_NE(p.message().find(bad), std::string::npos) << p.message();
  EXPECT_NE(p.message().find("shipped"), std::string::npos);

  const ColorPipeline missing = ColorPipeline::load("/no/such/config.ocio");
  EXPECT_NE(missing.message().find("does not exist"), std::string::npos) << missing.message();

  setenv("OCIO", bad.c_str(), 1);
  const ColorPipeline fromEnv = ColorPipeline::load();
  unsetenv("OCIO");
  EXPECT_NE(fromEnv.message().find("$OCIO"), std::string::npos) << fromEnv.message();
  EXPECT_FALSE(fromEnv.displays().empty());
}

// A studio config whose LUT is not where it says (a LUT folder not mounted): OCIO's validation says
// only "Config failed sanitycheck."; the message names the colour space and the LUT file.
TEST(ColorPipeline, AMissingLutIsNamed) {
  const std::string config = testing::TempDir() + "/missing-lut.ocio";
  std::ofstream(config) << "ocio_profile_version: 2\n"
                           "roles: {default: linear, scene_linear: linear}\n"
                           "displays:\n  sRGB:\n    - !<View> {name: Film, colorspace: film}\n"
                           "colorspaces:\n"
                           "  - !<ColorSpace>\n    name: linear\n"
                           "  - !<ColorSpace>\n    name: film\n"
                           "    from_scene_reference: !<FileTransform> {src: studio_film_lut.spi1d, interpolation: linear}\n";
  const ColorPipeline p = ColorPipeline::load(config);
  EXPECT_EQ(p.configPath(), ColorPipeline::shippedConfigPath());
  EXPECT_NE(p.message().find("\"film\""), std::string::npos) << p.message();
  EXPECT_NE(p.message().find("studio_film_lut.spi1d"), std::string::npos) << p.message();
}

}  // namespace
}  // namespace candela
