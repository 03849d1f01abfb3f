// The viewer's image area, headless: the comparison panes take the grid that shows each largest, and
// the pane under the cursor is the one whose pixel the readout and the zoom use.
#include "image_canvas.h"

#include <gtest/gtest.h>

namespace candela {
namespace {

TEST(ImageCanvas, PanesTakeTheGridThatShowsEachLargest) {
  ImageCanvas canvas(nullptr);  // layout and pane geometry need no window
  const ImageCanvas::Rect area{0.0f, 20.0f, 1070.0f, 700.0f};
  // Four 16:9 panes in the viewer's usual area: 2 x 2, each 535 wide, not a row of four 267 wide.
  canvas.layout(area, 16.0f / 9.0f, 4);
  EXPECT_EQ(canvas.columns(), 2);
  EXPECT_EQ(canvas.rows(), 2);
  EXPECT_FLOAT_EQ(canvas.paneRect(3).w, 535.0f);
  EXPECT_FLOAT_EQ(canvas.paneRect(3).x, 535.0f);
  EXPECT_FLOAT_EQ(canvas.paneRect(3).y, canvas.paneRect(1).y + canvas.paneRect(1).h);
  // A wide, low area keeps them in a row.
  canvas.layout({0.0f, 0.0f, 2400.0f, 300.0f}, 16.0f / 9.0f, 4);
  EXPECT_EQ(canvas.columns(), 4);
  EXPECT_EQ(canvas.rows(), 1);
  // Three panes: 2 x 2 with the last cell empty; the cursor over it reads the last pane.
  canvas.layout(area, 16.0f / 9.0f, 3);
  EXPECT_EQ(canvas.columns(), 2);
  EXPECT_EQ(canvas.rows(), 2);
  const ImageCanvas::Rect third = canvas.paneRect(2);
  EXPECT_EQ(canvas.paneAt(ImVec2(third.x + 10.0f, third.y + 10.0f)), 2);
  EXPECT_EQ(canvas.paneAt(ImVec2(third.x + third.w + 10.0f, third.y + 10.0f)), 2);
  const ImageCanvas::Rect second = canvas.paneRect(1);
  EXPECT_EQ(canvas.paneAt(ImVec2(second.x + 5.0f, second.y + 5.0f)), 1);
  // The panes keep the image's aspect.
  EXPECT_NEAR(third.w / third.h, 16.0f / 9.0f, 1e-3f);
  // Wipe: two images in one frame.
  canvas.setWipe(true);
  canvas.layout(area, 16.0f / 9.0f, 2);
  EXPECT_EQ(canvas.columns() * canvas.rows(), 1);
  EXPECT_EQ(canvas.paneAt(ImVec2(900.0f, 300.0f)), 0);
}

// 1:1 (key 1): one image pixel per screen pixel. An image smaller than the fitted pane is drawn at
// its own size, centred; a larger one is zoomed so that its pixels are the screen's. 0 fits again.
TEST(ImageCanvas, ActualPixels) {
  ImageCanvas canvas(nullptr);  // no window: one framebuffer pixel per window unit
  const ImageCanvas::Rect area{0.0f, 20.0f, 1070.0f, 700.0f};
  canvas.setOneToOne(true);
  canvas.layout(area, 16.0f / 9.0f, 1, 320);
  EXPECT_FLOAT_EQ(canvas.rect().w, 320.0f);
  EXPECT_FLOAT_EQ(canvas.rect().h, 180.0f);
  EXPECT_FLOAT_EQ(canvas.rect().x + 160.0f, 535.0f);
  canvas.layout(area, 16.0f / 9.0f, 1, 2140);  // twice the fitted width
  EXPECT_FLOAT_EQ(canvas.rect().w, 1070.0f);
  EXPECT_NEAR(canvas.view().u1 - canvas.view().u0, 0.5f, 1e-6f);
  canvas.resetZoom();
  EXPECT_FALSE(canvas.oneToOne());
  canvas.layout(area, 16.0f / 9.0f, 1, 320);
  EXPECT_FLOAT_EQ(canvas.rect().w, 1070.0f);
}

}  // namespace
}  // namespace candela
