// A 5 x 7 pixel font for the legends of the previews: digits, lower-case letters (upper
// case drawn as lower), and . , ; - + = : / % ( ) ³ µ; any other character is a '?'.
#ifndef SHEETMESH_WORKER_PIPELINE_PREVIEW_BITMAP_FONT_H_
#define SHEETMESH_WORKER_PIPELINE_PREVIEW_BITMAP_FONT_H_

#include <array>
#include <cstdint>

#include "absl/strings/string_view.h"
#include "worker/pipeline/preview/rgb_image.h"

namespace sheetmesh {

inline constexpr int kGlyphWidth = 5, kGlyphHeight = 7, kGlyphAdvance = 6;

// The width in pixels of `text` (UTF-8) drawn at `scale` pixels per font pixel.
int TextWidth(absl::string_view text, int scale = 1);

// Draws `text` (UTF-8) with its top-left corner at (x, y); pixels outside the image are
// left out.
void DrawText(RgbImage* image, int x, int y, absl::string_view text,
              const std::array<uint8_t, 3>& colour, int scale = 1);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_PREVIEW_BITMAP_FONT_H_
