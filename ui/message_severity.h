// How a viewer message reads: information (an auto exposure chosen, a file written), a warning (a
// volume that will render dark) or an error (an edit rejected, a file that could not be opened).
// The status bar and Help > Messages colour each by it. Messages come from the viewer, the render
// session and the renderer's validation, so the severity is read from their fixed wording.
#pragma once

#include <string>

namespace candela {

enum class Severity { Info, Warning, Error };

inline Severity messageSeverity(const std::string& text) {
  auto has = [&](const char* word) { return text.find(word) != std::string::npos; };
  if (text.rfind("warning", 0) == 0 || has("WARNING") || has(" warning: ")) return Severity::Warning;
  if (has("error") || has("failed") || has("rejected") || has("could not") || has("cannot") || has("expected") || has("DIFFERS") ||
      has("not applied") || has("no image yet") || has("nothing to"))
    return Severity::Error;
  return Severity::Info;
}

}  // namespace candela
