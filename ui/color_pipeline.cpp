#include "color_pipeline.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace candela {

std::string ColorPipeline::shippedConfigPath() { return std::string(CANDELA_ASSET_DIR) + "/ocio/config.ocio"; }

namespace {

// OCIO 2.1's validate() says only "Config failed sanitycheck." for some failures, a LUT file it
// cannot find among them (a studio config whose LUT folder is not mounted). Building each colour
// space's processor from scene_linear names the part that fails and the paths it tried.
void validateNamingWhatFails(const OCIO::ConstConfigRcPtr& config) {
  try {
    config->validate();
  } catch (const std::exception& e) {
    std::string detail;
    for (int i = 0; i < config->getNumColorSpaces() && detail.empty(); ++i) {
      const char* name = config->getColorSpaceNameByIndex(i);
      try {
        config->getProcessor(OCIO::ROLE_SCENE_LINEAR, name);
      } catch (const std::exception& inner) {
        detail = std::string(" Colour space \"") + name + "\": " + inner.what();
      }
    }
    throw std::runtime_error(e.what() + detail);
  }
}

OCIO::ConstConfigRcPtr loadValidated(const std::string& path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error("the file does not exist");
  OCIO::ConstConfigRcPtr config = OCIO::Config::CreateFromFile(path.c_str());
  validateNamingWhatFails(config);
  if (config->getNumDisplays() == 0) throw std::runtime_error("it defines no displays");
  if (!config->getColorSpace(OCIO::ROLE_SCENE_LINEAR)) throw std::runtime_error("it has no scene_linear role");
  return config;
}

}  // namespace

ColorPipeline ColorPipeline::load(const std::string& requested) {
  ColorPipeline p;
  std::string path = requested;
  std::string origin = "config";
  if (path.empty())
    if (const char* env = std::getenv("OCIO"); env && *env) path = env, origin = "$OCIO";
  if (!path.empty()) {
    try {
      p.config_ = loadValidated(path);
      p.configPath_ = path;
      return p;
    } catch (const std::exception& e) {
      p.message_ = "OCIO " + origin + " " + path + ": " + e.what() + "; using the shipped config instead";
    }
  }
  p.configPath_ = shippedConfigPath();
  p.config_ = loadValidated(p.configPath_);  // ours: a failure here is a broken install, and throws
  return p;
}

std::vector<std::string> ColorPipeline::displays() const {
  std::vector<std::string> out;
  for (int i = 0; i < config_->getNumDisplays(); ++i) out.emplace_back(config_->getDisplay(i));
  return out;
}

std::vector<std::string> ColorPipeline::views(const std::string& display) const {
  std::vector<std::string> out;
  for (int i = 0; i < config_->getNumViews(display.c_str()); ++i) out.emplace_back(config_->getView(display.c_str(), i));
  return out;
}

std::vector<std::string> ColorPipeline::looks() const {
  std::vector<std::string> out;
  for (int i = 0; i < config_->getNumLooks(); ++i) out.emplace_back(config_->getLookNameByIndex(i));
  return out;
}

DisplaySettings ColorPipeline::resolve(const DisplaySettings& s) const {
  DisplaySettings r = s;
  auto contains = [](const std::vector<std::string>& v, const std::string& x) {
    for (const auto& e : v)
      if (e == x) return true;
    return false;
  };
  if (!contains(displays(), r.display)) r.display = config_->getDefaultDisplay();
  if (!contains(views(r.display), r.view)) r.view = config_->getDefaultView(r.display.c_str());
  if (!r.look.empty() && !contains(looks(), r.look)) r.look.clear();
  return r;
}

OCIO::ConstProcessorRcPtr ColorPipeline::processor(const DisplaySettings& requested) const {
  const DisplaySettings s = resolve(requested);
  auto pipeline = OCIO::LegacyViewingPipeline::Create();
  auto displayView = OCIO::DisplayViewTransform::Create();
  displayView->setSrc(OCIO::ROLE_SCENE_LINEAR);
  displayView->setDisplay(s.display.c_str());
  displayView->setView(s.view.c_str());
  pipeline->setDisplayViewTransform(displayView);

  // Exposure: a gain of 2^stops on scene-linear values (linearCC runs before everything else).
  const double gain = std::exp2(static_cast<double>(s.exposure));
  auto exposure = OCIO::MatrixTransform::Create();
  const double scale[4] = {gain, gain, gain, 1.0};
  double m44[16], offset4[4];
  OCIO::MatrixTransform::Scale(m44, offset4, scale);
  exposure->setMatrix(m44);
  exposure->setOffset(offset4);
  pipeline->setLinearCC(exposure);

  if (s.channel != ChannelView::RGB) {
    // One channel (or Rec.709 luminance, our scene-linear primaries) copied to all three.
    double w[3] = {0.0, 0.0, 0.0};
    if (s.channel == ChannelView::Red) w[0] = 1.0;
    if (s.channel == ChannelView::Green) w[1] = 1.0;
    if (s.channel == ChannelView::Blue) w[2] = 1.0;
    if (s.channel == ChannelView::Luminance) w[0] = 0.2126, w[1] = 0.7152, w[2] = 0.0722;
    const double m[16] = {w[0], w[1], w[2], 0, w[0], w[1], w[2], 0, w[0], w[1], w[2], 0, 0, 0, 0, 1};
    auto channel = OCIO::MatrixTransform::Create();
    channel->setMatrix(m);
    pipeline->setChannelView(channel);
  }

  // An explicit look (or none) overrides any the view itself names.
  pipeline->setLooksOverrideEnabled(true);
  pipeline->setLooksOverride(s.look.c_str());

  if (s.gamma != 1.0f) {
    auto gamma = OCIO::ExponentTransform::Create();
    const double e = 1.0 / static_cast<double>(s.gamma);
    const double value[4] = {e, e, e, 1.0};
    gamma->setValue(value);
    pipeline->setDisplayCC(gamma);
  }
  return pipeline->getProcessor(config_, config_->getCurrentContext());
}

void ColorPipeline::applyCpu(const DisplaySettings& settings, std::vector<float>& rgb) const {
  auto cpu = processor(settings)->getDefaultCPUProcessor();
  OCIO::PackedImageDesc desc(rgb.data(), static_cast<long>(rgb.size() / 3), 1, 3);
  cpu->apply(desc);
}

}  // namespace candela
