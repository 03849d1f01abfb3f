// What the viewer shows and when it stops: plain structs that serialise to JSON like the renderer's
// settings. They are saved in screenshots' metadata and drive the Display panel (generated from
// visit(), as every other panel is).
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

// When progressive rendering stops (0: never). Separate from the scene's batch spp so look-dev can
// run open-ended while a scene still says what a final render takes.
struct ProgressLimits {
  int spp = 0;
  float time_s = 0.0f;

  template <class V>
  void visit(V& v) {
    v.field("spp", spp, "Stop refining at this many samples per pixel (0: never)", Range{0, 1 << 24});
    v.field("time_s", time_s, "Stop refining after this many seconds of rendering (0: never)", Range{0.0, 1e7});
  }
};

}  // namespace candela
