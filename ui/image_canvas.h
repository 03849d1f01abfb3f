// The image area of the viewer (tev's ImageCanvas): where the image sits in the window, its 2D zoom
// and pan (shared by every pane, so they stay in sync), the wipe divider between two images, the
// panes of a comparison (in the grid that shows each largest), and which pixel the readout shows. It knows nothing about scenes or rendering:
// it draws GlDisplays it is handed.
#pragma once

#include "gl_display.h"

#include <imgui.h>

#include <vector>

namespace candela {

class ImageCanvas {
 public:
  // A rectangle in window coordinates (top-left origin, window units).
  struct Rect {
    float x = 0, y = 0, w = 0, h = 0;
    bool contains(float px, float py) const { return px >= x && py >= y && px < x + w && py < y + h; }
    bool contains(ImVec2 p) const { return contains(p.x, p.y); }
  };
  // A window rectangle in framebuffer pixels (bottom-left origin).
  struct PixelRect {
    int x = 0, y = 0, w = 0, h = 0;
  };

  explicit ImageCanvas(GLFWwindow* window) : window_(window) {}

  // Fits `panes` images of `aspect` (width / height of one; 0: unknown) into `area`, centred, in the
  // grid of columns and rows that shows each largest (four 16:9 panes in a wide area: 2 x 2, not a
  // row of four a quarter the size). In wipe mode the panes share one frame. Call once a frame
  // before anything else.
  // With 1:1 on (setOneToOne) and `imageWidth` known, one image pixel covers one framebuffer pixel:
  // a smaller image is drawn smaller, centred; a larger one is zoomed about the view's centre.
  void layout(const Rect& area, float aspect, int panes = 1, int imageWidth = 0);
  const Rect& rect() const { return rect_; }  // every pane together
  int columns() const { return columns_; }
  int rows() const { return rows_; }
  // Pane i, row by row (the whole rectangle in wipe mode).
  Rect paneRect(int i) const;
  // The pane under window point p (the nearest cell when p is outside them all).
  int paneAt(ImVec2 p) const;
  // Which image is shown at p: the pane under it, or in wipe mode 0 left of the divider, 1 right.
  int imageAt(ImVec2 p) const { return wipe_ ? (p.x >= rect_.x + rect_.w * wipePosition_ ? 1 : 0) : paneAt(p); }
  PixelRect framebufferRect(const Rect& r) const;
  // Image coordinates (fractions, v down) under a window point of rectangle r, through the zoom.
  ImVec2 imageUv(const Rect& r, ImVec2 p) const;
  const ViewWindow& view() const { return view_; }

  // Ctrl+wheel zoom about the cursor, Shift+drag pan, and (in wipe mode) dragging the divider.
  // Returns true when it used the mouse this frame (the camera must not move then).
  bool handleMouse();
  void resetZoom();  // fit (also ends 1:1)
  void setOneToOne(bool on) { oneToOne_ = on; }
  bool oneToOne() const { return oneToOne_; }

  // Wipe: two images in one frame, split at a divider the user drags.
  bool wipe() const { return wipe_; }
  void setWipe(bool on) { wipe_ = on; }
  float wipePosition() const { return wipePosition_; }

  // Draws `display` into the rectangle (nearest filtering when zoomed past 2 screen pixels per
  // image pixel, unless `preview`).
  void draw(const GlDisplay& display, int imageWidth, bool preview) const;
  // Draws `left` and `right` split at the divider (wipe) or as two panes.
  void drawPair(const GlDisplay& left, const GlDisplay& right) const;
  // Draws n displays in the panes of the layout (or the first two split by the divider in wipe mode).
  void drawPanes(const std::vector<const GlDisplay*>& panes) const;
  // The divider line and its handle, over whatever was drawn.
  void drawDivider(ImDrawList* draw) const;

  // The pixel under the cursor (or the locked one) of an image of width x height, in whichever pane
  // the cursor is over; false when none.
  bool readoutPixel(int width, int height, int& px, int& py) const;
  bool readoutLocked() const { return readoutLocked_; }
  // L: lock the readout on the pixel under the cursor, or unlock it.
  void toggleReadoutLock(int width, int height);

 private:
  void updateView();
  GLFWwindow* window_;
  Rect rect_;
  int paneCount_ = 1, columns_ = 1, rows_ = 1;
  ViewWindow view_;
  float zoom_ = 1.0f;
  bool oneToOne_ = false;
  ImVec2 viewCenter_{0.5f, 0.5f};
  bool wipe_ = false;
  float wipePosition_ = 0.5f;
  bool draggingWipe_ = false;
  bool readoutLocked_ = false;
  int lockedX_ = 0, lockedY_ = 0;
};

}  // namespace candela
