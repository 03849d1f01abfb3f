// ImGui widgets generated from a struct's visit(): the same field list that reads and writes JSON
// draws the panel, with the field's doc string as its tooltip and its Range as the widget's clamp.
// Nothing is copied widget by widget, so a new setting appears in the UI the moment it is declared.
#pragma once

#include "fields.h"

#include <imgui.h>
#include <imgui_stdlib.h>

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

  template <class T>
  void field(const char* key, T& value, const char* doc, Range range = {}) {
    ImGui::PushID(key);
    edit(key, value, range);
    tooltip(doc, range);
    ImGui::PopID();
  }
  template <class T>
  void required(const char* key, T& value, const char* doc, Range range = {}) {
    field(key, value, doc, range);
  }
  template <class S>
  void object(const char* key, S& value, const char* doc) {
    const bool open = ImGui::TreeNodeEx(key, ImGuiTreeNodeFlags_None);
    tooltip(doc, {});
    if (open) {
      value.visit(*this);
      ImGui::TreePop();
    }
  }

 private:
  static bool bounded(Range r) { return r.min > -1e29 || r.max < 1e29; }
  static float lo(Range r) { return r.min > -1e29 ? static_cast<float>(r.min) : -FLT_MAX / 2; }
  static float hi(Range r) { return r.max < 1e29 ? static_cast<float>(r.max) : FLT_MAX / 2; }

  void tooltip(const char* doc, Range range) {
    if (!ImGui::IsItemHovered() || !doc) return;
    if (bounded(range))
      ImGui::SetTooltip("%s\nRange: %.4g to %.4g", doc, range.min, range.max);
    else
      ImGui::SetTooltip("%s", doc);
  }

  void edit(const char* key, bool& v, Range) { changed |= ImGui::Checkbox(key, &v); }
  void edit(const char* key, int& v, Range r) {
    const float speed = std::max(0.05f, std::abs(static_cast<float>(v)) * 0.01f);
    const int a = r.min > -1e9 ? static_cast<int>(r.min) : INT32_MIN / 2, b = r.max < 1e9 ? static_cast<int>(r.max) : INT32_MAX / 2;
    changed |= ImGui::DragInt(key, &v, speed, a, b, "%d", ImGuiSliderFlags_AlwaysClamp);
  }
  void edit(const char* key, uint32_t& v, Range) { changed |= ImGui::InputScalar(key, ImGuiDataType_U32, &v); }
  void edit(const char* key, float& v, Range r) {
    if (bounded(r) && r.max - r.min <= 2.0) {
      changed |= ImGui::SliderFloat(key, &v, lo(r), hi(r), "%.3f", ImGuiSliderFlags_AlwaysClamp);
    } else {
      const float speed = std::max(1e-3f, std::abs(v) * 0.01f);
      changed |= ImGui::DragFloat(key, &v, speed, lo(r), hi(r), "%.4g", ImGuiSliderFlags_AlwaysClamp);
    }
  }
  void edit(const char* key, std::string& v, Range) {
    if (auto it = choices.find(key); it != choices.end()) {
      if (ImGui::BeginCombo(key, v.empty() ? "(none)" : v.c_str())) {
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
    changed |= ImGui::InputText(key, &v, ImGuiInputTextFlags_EnterReturnsTrue);
  }
  void edit(const char* key, Vec3& v, Range r) {
    const std::string k(key);
    bool c;
    if (k.find("color") != std::string::npos || k.find("albedo") != std::string::npos) {
      ImGuiColorEditFlags flags = ImGuiColorEditFlags_Float;
      if (r.max > 1.0) flags |= ImGuiColorEditFlags_HDR;
      c = ImGui::ColorEdit3(key, &v.x, flags);
    } else {
      c = ImGui::DragFloat3(key, &v.x, 0.01f, 0.0f, 0.0f, "%.3f");
    }
    if (c) v = glm::clamp(v, Vec3(lo(r)), Vec3(hi(r)));
    changed |= c;
  }
  void edit(const char* key, std::pair<int, int>& v, Range r) {
    int xy[2] = {v.first, v.second};
    if (ImGui::DragInt2(key, xy, 1.0f, static_cast<int>(std::max(r.min, -1e9)), static_cast<int>(std::min(r.max, 1e9)), "%d",
                        ImGuiSliderFlags_AlwaysClamp)) {
      v = {xy[0], xy[1]};
      changed = true;
    }
  }
  template <class E, class = decltype(EnumNames<E>::get())>
  void edit(const char* key, E& v, Range) {
    if (ImGui::BeginCombo(key, enumName(v))) {
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
