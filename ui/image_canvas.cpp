#include "image_canvas.h"

#include <algorithm>
#include <cmath>

namespace candela {

void ImageCanvas::layout(const Rect& area, float aspect, int panes, int imageWidth) {
  rect_ = area;
  paneCount_ = std::max(1, panes);
  columns_ = rows_ = 1;
  if (!wipe_ && paneCount_ > 1) {
    // The grid whose panes are widest; at a tie, the one with fewer rows.
    float best = 0.0f;
    for (int columns = 1; columns <= paneCount_; ++columns) {
      const int rows = (paneCount_ + columns - 1) / columns;
      const float width = aspect > 0.0f ? std::min(area.w / columns, area.h / rows * aspect) : area.w / columns;
      if (width > best * 1.001f) best = width, columns_ = columns, rows_ = rows;
    }
  }
  if (aspect <= 0.0f) return;
  aspect *= static_cast<float>(columns_) / static_cast<float>(rows_);
  if (area.w / area.h > aspect) {
    rect_.w = area.h * aspect;
    rect_.x = area.x + 0.5f * (area.w - rect_.w);
  } else {
    rect_.h = area.w / aspect;
    rect_.y = area.y + 0.5f * (area.h - rect_.h);
  }
  if (!oneToOne_ || imageWidth <= 0) return;
  // One image pixel per framebuffer pixel: the pane's width in window units that holds imageWidth.
  float scale = 1.0f;
  if (window_) {
    int fbw = 0, fbh = 0, ww = 0, wh = 0;
    glfwGetFramebufferSize(window_, &fbw, &fbh);
    glfwGetWindowSize(window_, &ww, &wh);
    scale = static_cast<float>(fbw) / static_cast<float>(std::max(1, ww));
  }
  const float wanted = static_cast<float>(imageWidth) / std::max(1e-3f, scale);
  const float fitted = rect_.w / static_cast<float>(wipe_ ? 1 : columns_);
  if (wanted <= fitted) {
    const float shrink = wanted / fitted;
    const Rect whole = rect_;
    rect_.w *= shrink, rect_.h *= shrink;
    rect_.x = whole.x + 0.5f * (whole.w - rect_.w);
    rect_.y = whole.y + 0.5f * (whole.h - rect_.h);
    zoom_ = 1.0f;
  } else {
    zoom_ = wanted / fitted;
  }
  updateView();
}

ImageCanvas::Rect ImageCanvas::paneRect(int i) const {
  if (wipe_ || paneCount_ <= 1) return rect_;
  const float w = rect_.w / static_cast<float>(columns_), h = rect_.h / static_cast<float>(rows_);
  return Rect{rect_.x + w * static_cast<float>(i % columns_), rect_.y + h * static_cast<float>(i / columns_), w, h};
}

int ImageCanvas::paneAt(ImVec2 p) const {
  if (wipe_ || paneCount_ <= 1) return 0;
  const int column = std::clamp(static_cast<int>(std::floor((p.x - rect_.x) / std::max(1.0f, rect_.w) * columns_)), 0, columns_ - 1);
  const int row = std::clamp(static_cast<int>(std::floor((p.y - rect_.y) / std::max(1.0f, rect_.h) * rows_)), 0, rows_ - 1);
  return std::min(paneCount_ - 1, row * columns_ + column);
}

ImageCanvas::PixelRect ImageCanvas::framebufferRect(const Rect& r) const {
  int fbw, fbh, ww, wh;
  glfwGetFramebufferSize(window_, &fbw, &fbh);
  glfwGetWindowSize(window_, &ww, &wh);
  const float sx = static_cast<float>(fbw) / std::max(1, ww), sy = static_cast<float>(fbh) / std::max(1, wh);
  return {static_cast<int>(r.x * sx), fbh - static_cast<int>((r.y + r.h) * sy), static_cast<int>(r.w * sx), static_cast<int>(r.h * sy)};
}

ImVec2 ImageCanvas::imageUv(const Rect& r, ImVec2 p) const {
  const float fx = (p.x - r.x) / std::max(1.0f, r.w), fy = (p.y - r.y) / std::max(1.0f, r.h);
  return ImVec2(view_.u0 + fx * (view_.u1 - view_.u0), view_.v0 + fy * (view_.v1 - view_.v0));
}

void ImageCanvas::updateView() {
  zoom_ = std::clamp(zoom_, 1.0f, 64.0f);
  const float half = 0.5f / zoom_;
  viewCenter_.x = std::clamp(viewCenter_.x, half, 1.0f - half);
  viewCenter_.y = std::clamp(viewCenter_.y, half, 1.0f - half);
  view_ = {viewCenter_.x - half, viewCenter_.y - half, viewCenter_.x + half, viewCenter_.y + half};
}

void ImageCanvas::resetZoom() {
  oneToOne_ = false;
  zoom_ = 1.0f;
  viewCenter_ = ImVec2(0.5f, 0.5f);
  updateView();
}

bool ImageCanvas::handleMouse() {
  ImGuiIO& io = ImGui::GetIO();
  const Rect& r = rect_;
  const bool over = !io.WantCaptureMouse && r.contains(io.MousePos);
  // Ctrl+wheel zooms the image about the cursor (2D only: the camera and the render do not change,
  // so accumulation goes on).
  if (over && io.KeyCtrl && io.MouseWheel != 0.0f) {
    const Rect pane = paneRect(paneAt(io.MousePos));
    const ImVec2 before = imageUv(pane, io.MousePos);
    oneToOne_ = false;
    zoom_ *= std::exp(io.MouseWheel * 0.2f);
    updateView();
    const ImVec2 after = imageUv(pane, io.MousePos);
    viewCenter_.x += before.x - after.x;
    viewCenter_.y += before.y - after.y;
    updateView();
    return true;
  }
  if (io.KeyShift && over && io.MouseDown[0]) {
    const Rect pane = paneRect(0);
    viewCenter_.x -= io.MouseDelta.x / std::max(1.0f, pane.w) / zoom_;
    viewCenter_.y -= io.MouseDelta.y / std::max(1.0f, pane.h) / zoom_;
    updateView();
    return true;
  }
  // In wipe mode a left drag near the divider moves it.
  if (wipe_) {
    const float divider = r.x + r.w * wipePosition_;
    if (!draggingWipe_ && over && io.MouseClicked[0] && std::abs(io.MousePos.x - divider) < 8.0f) draggingWipe_ = true;
    if (draggingWipe_) {
      if (!io.MouseDown[0]) draggingWipe_ = false;
      wipePosition_ = std::clamp((io.MousePos.x - r.x) / std::max(1.0f, r.w), 0.0f, 1.0f);
      return true;
    }
  }
  return false;
}

void ImageCanvas::draw(const GlDisplay& display, int imageWidth, bool preview) const {
  const PixelRect p = framebufferRect(rect_);
  display.blitToWindow(p.x, p.y, p.w, p.h, !preview && p.w >= 2 * imageWidth * (view_.u1 - view_.u0), view_);
}

void ImageCanvas::drawPair(const GlDisplay& left, const GlDisplay& right) const {
  drawPanes({&left, &right});
}

void ImageCanvas::drawPanes(const std::vector<const GlDisplay*>& panes) const {
  const int n = static_cast<int>(panes.size());
  for (int i = 0; i < n; ++i) {
    if (!panes[static_cast<size_t>(i)]) continue;
    if (wipe_ && n == 2) {
      // The first image left of the divider, the second right of it, in the same frame.
      const PixelRect p = framebufferRect(rect_);
      const float a = i == 0 ? 0.0f : wipePosition_, b = i == 0 ? wipePosition_ : 1.0f;
      panes[static_cast<size_t>(i)]->blitToWindow(p.x, p.y, p.w, p.h, false, view_, a, b);
      continue;
    }
    const PixelRect p = framebufferRect(paneRect(i));
    panes[static_cast<size_t>(i)]->blitToWindow(p.x, p.y, p.w, p.h, false, view_);
  }
}

void ImageCanvas::drawDivider(ImDrawList* draw) const {
  if (!wipe_) return;
  const float x = rect_.x + rect_.w * wipePosition_;
  draw->AddLine(ImVec2(x, rect_.y), ImVec2(x, rect_.y + rect_.h), IM_COL32(255, 255, 255, 200), 2.0f);
  draw->AddCircleFilled(ImVec2(x, rect_.y + rect_.h * 0.5f), 6.0f, IM_COL32(255, 255, 255, 220));
}

bool ImageCanvas::readoutPixel(int width, int height, int& px, int& py) const {
  const ImGuiIO& io = ImGui::GetIO();
  if (readoutLocked_) {
    px = lockedX_, py = lockedY_;
  } else if (rect_.contains(io.MousePos)) {
    const ImVec2 uv = imageUv(paneRect(paneAt(io.MousePos)), io.MousePos);
    px = static_cast<int>(uv.x * width);
    py = static_cast<int>(uv.y * height);
  } else {
    return false;
  }
  return px >= 0 && px < width && py >= 0 && py < height;
}

void ImageCanvas::toggleReadoutLock(int width, int height) {
  readoutLocked_ = !readoutLocked_;
  if (readoutLocked_ && width > 0 && height > 0) {
    const ImVec2 uv = imageUv(paneRect(paneAt(ImGui::GetIO().MousePos)), ImGui::GetIO().MousePos);
    lockedX_ = std::clamp(static_cast<int>(uv.x * width), 0, width - 1);
    lockedY_ = std::clamp(static_cast<int>(uv.y * height), 0, height - 1);
  }
}

}  // namespace candela
