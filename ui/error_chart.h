// Error versus time on log-log axes, one line per pane, drawn with ImGui's draw list (ImPlot is not
// in Debian). Kept small and separate from the viewer.
#pragma once

#include "comparison_session.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace candela {

inline ImU32 paneColor(size_t i) {
  static const ImU32 colors[] = {IM_COL32(230, 120, 90, 255), IM_COL32(90, 170, 230, 255), IM_COL32(120, 210, 110, 255),
                                 IM_COL32(220, 200, 90, 255)};
  return colors[i % 4];
}

// relMSE (y) against render seconds (x), both logarithmic, in the box at `origin` of `size`.
inline void drawErrorChart(ImDrawList* draw, const ComparisonFrame& frame, ImVec2 origin, ImVec2 size) {
  double x0 = 1e30, x1 = -1e30, y0 = 1e30, y1 = -1e30;
  for (const auto& p : frame.panes)
    for (const auto& s : p.series)
      if (s.seconds > 0.0 && s.relmse > 0.0) {
        x0 = std::min(x0, std::log10(s.seconds)), x1 = std::max(x1, std::log10(s.seconds));
        y0 = std::min(y0, std::log10(s.relmse)), y1 = std::max(y1, std::log10(s.relmse));
      }
  draw->AddRectFilled(origin, ImVec2(origin.x + size.x, origin.y + size.y), IM_COL32(25, 25, 28, 255));
  if (x0 > x1) {
    draw->AddText(ImVec2(origin.x + 8, origin.y + 8), IM_COL32(150, 150, 150, 255),
                  frame.hasReference ? "waiting for samples" : "no reference: load an EXR or render one");
    return;
  }
  // Whole decades around the data, so slopes read at a glance.
  x0 = std::floor(x0), x1 = std::max(std::ceil(x1), x0 + 1.0), y0 = std::floor(y0), y1 = std::max(std::ceil(y1), y0 + 1.0);
  const float left = 42.0f, bottom = 18.0f;
  auto map = [&](double lx, double ly) {
    return ImVec2(origin.x + left + static_cast<float>((lx - x0) / (x1 - x0)) * (size.x - left - 6.0f),
                  origin.y + 4.0f + static_cast<float>((y1 - ly) / (y1 - y0)) * (size.y - bottom - 8.0f));
  };
  char text[32];
  for (double d = x0; d <= x1 + 1e-9; d += 1.0) {
    draw->AddLine(map(d, y0), map(d, y1), IM_COL32(60, 60, 66, 255));
    std::snprintf(text, sizeof(text), "%gs", std::pow(10.0, d));
    const float labelX = std::min(map(d, y0).x - 8.0f, origin.x + size.x - ImGui::CalcTextSize(text).x);  // the last one inside the box
    draw->AddText(ImVec2(labelX, origin.y + size.y - bottom + 2.0f), IM_COL32(150, 150, 150, 255), text);
  }
  for (double d = y0; d <= y1 + 1e-9; d += 1.0) {
    draw->AddLine(map(x0, d), map(x1, d), IM_COL32(60, 60, 66, 255));
    std::snprintf(text, sizeof(text), "1e%d", static_cast<int>(d));
    draw->AddText(ImVec2(origin.x + 2.0f, map(x0, d).y - 7.0f), IM_COL32(150, 150, 150, 255), text);
  }
  for (size_t i = 0; i < frame.panes.size(); ++i) {
    const auto& series = frame.panes[i].series;
    for (size_t k = 1; k < series.size(); ++k) {
      if (series[k - 1].relmse <= 0.0 || series[k].relmse <= 0.0) continue;
      draw->AddLine(map(std::log10(series[k - 1].seconds), std::log10(series[k - 1].relmse)),
                    map(std::log10(series[k].seconds), std::log10(series[k].relmse)), paneColor(i), 2.0f);
    }
  }
}

// The same in a panel, at the cursor, with a tooltip saying what it shows.
inline void drawErrorChart(const ComparisonFrame& frame, ImVec2 size) {
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton("error chart", size);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("relMSE against the reference versus render time, log-log; an unbiased estimator falls as 1/t.\n%s", kRelMseFormula);
  drawErrorChart(ImGui::GetWindowDrawList(), frame, origin, size);
}

}  // namespace candela
