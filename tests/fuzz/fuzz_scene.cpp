// libFuzzer target: the scene parser with --set edits. The input is a scene JSON document, then
// optionally lines of KEY=VALUE edits after a line "--set". Any outcome but a parsed scene or an
// InputError (a crash, a sanitizer report, another exception, a hang) is a finding.
#include "scene_desc.h"

#include <cstdint>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const size_t split = input.find("\n--set\n");
  const std::string text = input.substr(0, split);
  std::vector<std::string> edits;
  if (split != std::string::npos) {
    size_t start = split + 7;
    while (start <= input.size()) {
      const size_t end = input.find('\n', start);
      edits.push_back(input.substr(start, end == std::string::npos ? std::string::npos : end - start));
      if (end == std::string::npos) break;
      start = end + 1;
    }
  }
  try {
    candela::Json doc = candela::parseJsonText(text, "fuzz.json");
    for (const auto& e : edits) candela::applySetting(doc, e, "fuzz.json (--set)");
    const candela::SceneDesc scene = candela::parseSceneDesc(doc, "fuzz.json");
    // Round trip: what was accepted must serialise.
    (void)candela::sceneToJson(scene).dump();
  } catch (const candela::InputError&) {
  }
  return 0;
}
