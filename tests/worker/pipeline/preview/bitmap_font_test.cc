#include "worker/pipeline/preview/bitmap_font.h"

#include <gtest/gtest.h>

#include "worker/pipeline/preview/previews.h"

namespace sheetmesh {
namespace {

RgbImage Blank(int w, int h) {
  RgbImage im;
  im.width = w;
  im.height = h;
  im.rgb.assign(3 * w * h, 0);
  return im;
}

int Inked(const RgbImage& im, int x0, int x1) {
  int n = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = x0; x < x1; ++x) n += im.rgb[3 * (y * im.width + x)] != 0;
  return n;
}

TEST(BitmapFontTest, TextIsSixPixelsACharacterLessTheLastGap) {
  EXPECT_EQ(TextWidth(""), 0);
  EXPECT_EQ(TextWidth("ab"), 11);
  EXPECT_EQ(TextWidth("ab", 2), 22);
  EXPECT_EQ(TextWidth("0.5 µm"), TextWidth("0.5 um")) << "µ is one character, not two bytes";
}

TEST(BitmapFontTest, GlyphsAreDrawnWhereTheTextIsAndClippedAtTheEdge) {
  RgbImage im = Blank(40, 10);
  DrawText(&im, 1, 1, "1 m", {255, 255, 255});
  EXPECT_EQ(Inked(im, 1, 6), 10) << "the '1': 10 pixels";
  EXPECT_EQ(Inked(im, 7, 12), 0) << "the space";
  EXPECT_GT(Inked(im, 13, 18), 0) << "the 'm'";
  EXPECT_EQ(Inked(im, 18, 40), 0);
  // Upper case is drawn as lower case; an unknown character as '?'; beyond the edge, nothing.
  RgbImage a = Blank(6, 8), b = Blank(6, 8), q = Blank(6, 8), u = Blank(6, 8);
  DrawText(&a, 0, 0, "M", {9, 9, 9});
  DrawText(&b, 0, 0, "m", {9, 9, 9});
  DrawText(&q, 0, 0, "?", {9, 9, 9});
  DrawText(&u, 0, 0, "☃", {9, 9, 9});
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(q.rgb, u.rgb);
  DrawText(&a, 4, 5, "mmmm", {9, 9, 9});  // mostly outside: no crash
}

}  // namespace
}  // namespace sheetmesh
