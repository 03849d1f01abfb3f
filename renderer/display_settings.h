// How an image is shown: exposure and the OCIO display pipeline's choices. A plain struct that
// serialises to JSON; the renderer never applies it (it renders scene-linear radiance), but scene
// files keep it so a saved look reopens as it was seen, and the CLI's PNG output uses its exposure.
#pragma once

#include "fields.h"

#include <string>

namespace candela {

enum class ChannelView { RGB, Red, Green, Blue, Luminance };
template <>
struct EnumNames<ChannelView> {
  static const std::vector<std::pair<ChannelView, const char*>>& get() {
    static const std::vector<std::pair<ChannelView, const char*>> v{{ChannelView::RGB, "rgb"},
                                                                    {ChannelView::Red, "r"},
                                                                    {ChannelView::Green, "g"},
                                                                    {ChannelView::Blue, "b"},
                                                                    {ChannelView::Luminance, "luminance"}};
    return v;
  }
};

// The display pipeline, in the order of OCIO's viewing pipeline: exposure (scene-linear, before the
// view), channel view, look, display/view transform, gamma (display-referred, after the view).
struct DisplaySettings {
  float exposure = 0.0f;  // stops
  ChannelView channel = ChannelView::RGB;
  std::string look;       // "" = none
  std::string display;    // "" = the config's default display
  std::string view;       // "" = the display's default view
  float gamma = 1.0f;
  // No exposure given (a scene file without display.exposure, an opened VDB): the viewer and PNG
  // outputs choose one from the first image (autoExposureStops) and keep it. Not a schema field: a
  // scene file says it by leaving "exposure" out, and sceneToJson leaves it out while this holds.
  bool autoExposure = false;

  template <class V>
  void visit(V& v) {
    v.field("exposure", exposure, "Exposure in stops, applied to scene-linear values before the view transform", Range{-20.0, 20.0});
    v.field("channel", channel, "Channel view: rgb, one channel as grey, or Rec.709 luminance (scene-linear, before the view)");
    v.field("look", look, "OCIO look applied before the view transform (empty: none)");
    v.field("display", display, "OCIO display (empty: the config's default)");
    v.field("view", view, "OCIO view transform for the display (empty: the display's default)");
    v.field("gamma", gamma, "Display gamma after the view transform: out = in^(1/gamma)", Range{0.1, 10.0});
  }
};

}  // namespace candela
