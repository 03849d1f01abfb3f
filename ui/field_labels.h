// What the panels call a settings field: words an artist reads ("Density", "Anisotropy"), with the
// JSON name kept for the tooltip, the CLI's --set and the scene files. Fields without an entry are
// named from their key ("guided_probability" reads "Guided probability").
#pragma once

#include <cctype>
#include <map>
#include <string>

namespace candela {

inline std::string fieldLabel(const std::string& key) {
  static const std::map<std::string, std::string> words{
      {"exposure", "Exposure (stops)"},
      {"view", "View transform"},
      {"sigma_t_scale", "Density"},
      {"albedo", "Colour (albedo)"},
      {"g", "Anisotropy (forward > 0)"},
      {"color", "Colour"},
      {"fov_y", "Field of view (vertical, degrees)"},
      {"look_at", "Look at"},
      {"resolution", "Resolution (pixels)"},
      {"spp", "Samples per pixel"},
      {"time_s", "Time (seconds)"},
      {"seed", "Random seed"},
      {"max_depth", "Most bounces"},
      {"adaptive_split", "Adaptive sampling (samples per block, 0: off)"},
      {"file", "VDB file"},
      {"cone_angle_deg", "Cone angle (degrees)"},
      {"cone_falloff_deg", "Cone softness (degrees)"},
      {"rotate_deg", "Rotate (degrees)"},
      {"preset", "Strategy"},
      {"light_sampling", "Sample the flames as lights"},
      {"emission_weight", "Emission weight of the majorant"},
      {"russian_roulette_depth", "Russian roulette from bounce"},
  };
  if (auto it = words.find(key); it != words.end()) return it->second;
  std::string label = key;
  std::string unit;
  auto ends = [&](const std::string& suffix) { return label.size() > suffix.size() && label.compare(label.size() - suffix.size(), suffix.size(), suffix) == 0; };
  if (ends("_deg")) label.resize(label.size() - 4), unit = " (degrees)";
  else if (ends("_s")) label.resize(label.size() - 2), unit = " (seconds)";
  for (char& c : label)
    if (c == '_') c = ' ';
  if (!label.empty()) label[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(label[0])));
  return label + unit;
}

}  // namespace candela
