// What the viewer shows and when it stops: plain structs that serialise to JSON like the renderer's
// settings. They are saved in screenshots' metadata and drive the Display panel (generated from
// visit(), as every other panel is).
#pragma once

#include "display_settings.h"
#include "fields.h"

#include <string>

namespace candela {

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
