// ImGui widgets generated from a struct's visit(): the same field list that reads and writes JSON
// draws the panel, each field labelled in words (field_labels.h) with its doc string, JSON name and
// Range in the tooltip, and its Range as the widget's clamp.
// Nothing is copied widget by widget, so a new setting appears in the UI the moment it is declared.
#pragma once

#include "field_labels.h"
#include "fields.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <map>
#include <string>

namespace candela {

class ParamEditor {
 public:
  static constexpr bool kReading = false;
  static constexpr bool kWriting = true;  // optional sub-objects show only when present
  bool has(const char*) const { return true; }

  // True when any widget changed a value this frame.
  bool changed = false;
  // Set when the user picked a strategy preset (the "preset" field): the caller resets the strategy.
  std::string presetChosen;
  // String fields offered as a menu of choices, by key (strategy presets, OCIO displays/views/looks).
  std::map<std::string, std::vector<std::string>> choices;
  // The "direction" field as azimuth and elevation: +1 of where it points (a spot), -1 of where the
  // light comes from (a sun, whose direction is where its light travels); 0 as a vector.
  int directionSense = 0;

  template <class T>
  void field(const char* key, T& value, const char* doc, Range range = {}) {
    ImGui::PushID(key);
    label_ = fieldLabel(key);
    edit(key, value, range);
    tooltip(key, doc, range);
    ImGui::PopID();
  }
  template <class T>
  void required(const char* key, T& value, const char* doc, Range range = {}) {
    field(key, value, doc, range);
  }
  template <class S>
  void object(const char* key, S& value, const char* doc) {
    const bool open = ImGui::TreeNodeEx(key, ImGuiTreeNodeFlags_None, "%s", fieldLabel(key).c_str());
    tooltip(key, doc, {});
    if (open) {
      value.visit(*this);
      ImGui::TreePop();
    }
  }

 private:
  static bool bounded(Range r) { return r.min > -1e29 || r.max < 1e29; }
  static float lo(Range r) { return r.min > -1e29 ? static_cast<float>(r.min) : -FLT_MAX / 2; }
  static float hi(Range r) { return r.max < 1e29 ? static_cast<float>(r.max) : FLT_MAX / 2; }

  void tooltip(const char* key, const char* doc, Range range) {
    if (!ImGui::IsItemHovered() || !doc) return;
    if (bounded(range))
      ImGui::SetTooltip("%s\nRange: %.4g to %.4g\nIn scene files and --set: %s", doc, range.min, range.max, key);
    else
      ImGui::SetTooltip("%s\nIn scene files and --set: %s", doc, key);
  }
  // The widget's label: the field in words (the key stays the widget's ID, pushed by field()).
  const char* label() const { return label_.c_str(); }
  std::string label_;

  void edit(const char*, bool& v, Range) { changed |= ImGui::Checkbox(label(), &v); }
  void edit(const char*, int& v, Range r) {
    const float speed = std::max(0.05f, std::abs(static_cast<float>(v)) * 0.01f);
    const int a = r.min > -1e9 ? static_cast<int>(r.min) : INT32_MIN / 2, b = r.max < 1e9 ? static_cast<int>(r.max) : INT32_MAX / 2;
    changed |= ImGui::DragInt(label(), &v, speed, a, b, "%d", ImGuiSliderFlags_AlwaysClamp);
  }
  void edit(const char*, uint32_t& v, Range) { changed |= ImGui::InputScalar(label(), ImGuiDataType_U32, &v); }
  void edit(const char*, float& v, Range r) {
    if (bounded(r) && r.max - r.min <= 2.0) {
      changed |= ImGui::SliderFloat(label(), &v, lo(r), hi(r), "%.3f", ImGuiSliderFlags_AlwaysClamp);
    } else {
      const float speed = std::max(1e-3f, std::abs(v) * 0.01f);
      changed |= ImGui::DragFloat(label(), &v, speed, lo(r), hi(r), "%.4g", ImGuiSliderFlags_AlwaysClamp);
    }
  }
  void edit(const char* key, std::string& v, Range) {
    if (auto it = choices.find(key); it != choices.end()) {
      if (ImGui::BeginCombo(label(), v.empty() ? "(none)" : v.c_str())) {
        for (const auto& name : it->second)
          if (ImGui::Selectable(name.empty() ? "(none)" : name.c_str(), name == v)) {
            if (std::string(key) == "preset") presetChosen = name;
            v = name;
            changed = true;
          }
        ImGui::EndCombo();
      }
      return;
    }
    // Text applies on Enter: a half-typed file name must not trigger a load.
    changed |= ImGui::InputText(label(), &v, ImGuiInputTextFlags_EnterReturnsTrue);
  }
  void edit(const char* key, Vec3& v, Range r) {
    const std::string k(key);
    bool c;
    if (k.find("color") != std::string::npos || k.find("albedo") != std::string::npos) {
      ImGuiColorEditFlags flags = ImGuiColorEditFlags_Float;
      if (r.max > 1.0) flags |= ImGuiColorEditFlags_HDR;
      c = ImGui::ColorEdit3(label(), &v.x, flags);
    } else if (k == "direction" && directionSense != 0) {
      c = editAzimuthElevation(v);
    } else {
      c = ImGui::DragFloat3(label(), &v.x, 0.01f, 0.0f, 0.0f, "%.3f");
    }
    if (c) v = glm::clamp(v, Vec3(lo(r)), Vec3(hi(r)));
    changed |= c;
  }
  void edit(const char*, std::pair<int, int>& v, Range r) {
    int xy[2] = {v.first, v.second};
    if (ImGui::DragInt2(label(), xy, 1.0f, static_cast<int>(std::max(r.min, -1e9)), static_cast<int>(std::min(r.max, 1e9)), "%d",
                        ImGuiSliderFlags_AlwaysClamp)) {
      v = {xy[0], xy[1]};
      changed = true;
    }
  }
  // Azimuth about +Y from +Z towards +X and elevation above the horizon, in degrees, of the direction
  // (times directionSense); the vector keeps unit length.
  bool editAzimuthElevation(Vec3& v) {
    const Vec3 d = glm::length(v) > 0.0f ? glm::normalize(v) * static_cast<float>(directionSense) : Vec3(0, 1, 0);
    float azimuth = glm::degrees(std::atan2(d.x, d.z));
    float elevation = glm::degrees(std::asin(std::clamp(d.y, -1.0f, 1.0f)));
    const char* what = directionSense < 0 ? "Sun" : "Aim";
    bool c = ImGui::DragFloat((std::string(what) + " azimuth (degrees)").c_str(), &azimuth, 0.5f, -180.0f, 180.0f, "%.1f",
                              ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Compass angle about the up axis: 0 faces +Z, 90 faces +X\nIn scene files and --set: direction");
    c |= ImGui::DragFloat((std::string(what) + " elevation (degrees)").c_str(), &elevation, 0.5f, -90.0f, 90.0f, "%.1f",
                          ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Angle above the horizon (90: straight up)\nIn scene files and --set: direction");
    if (c) {
      const float az = glm::radians(azimuth), el = glm::radians(elevation);
      v = static_cast<float>(directionSense) * Vec3(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
    }
    return c;
  }
  template <class E, class = decltype(EnumNames<E>::get())>
  void edit(const char*, E& v, Range) {
    if (ImGui::BeginCombo(label(), enumName(v))) {
      for (const auto& [e, name] : EnumNames<E>::get())
        if (ImGui::Selectable(name, e == v)) {
          changed |= e != v;
          v = e;
        }
      ImGui::EndCombo();
    }
  }
};

}  // namespace candela
