#include "worker/pipeline/preview/bitmap_font.h"

#include <vector>

#include "worker/pipeline/preview/rgb_image.h"

namespace sheetmesh {
namespace {

// Seven rows per glyph, top to bottom; bit 4 is the leftmost pixel.
struct Glyph {
  char32_t code;
  std::array<uint8_t, 7> rows;
};

constexpr Glyph kGlyphs[] = {
    {U' ', {0, 0, 0, 0, 0, 0, 0}},
    {U'0', {0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110}},
    {U'1', {0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
    {U'2', {0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111}},
    {U'3', {0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110}},
    {U'4', {0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010}},
    {U'5', {0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110}},
    {U'6', {0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110}},
    {U'7', {0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000}},
    {U'8', {0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110}},
    {U'9', {0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100}},
    {U'.', {0, 0, 0, 0, 0, 0b01100, 0b01100}},
    {U',', {0, 0, 0, 0, 0b01100, 0b00100, 0b01000}},
    {U'-', {0, 0, 0, 0b11111, 0, 0, 0}},
    {U'+', {0, 0b00100, 0b00100, 0b11111, 0b00100, 0b00100, 0}},
    {U'=', {0, 0, 0b11111, 0, 0b11111, 0, 0}},
    {U':', {0, 0b01100, 0b01100, 0, 0b01100, 0b01100, 0}},
    {U';', {0, 0b01100, 0b01100, 0, 0b01100, 0b00100, 0b01000}},
    {U'/', {0, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0}},
    {U'%', {0b11000, 0b11001, 0b00010, 0b00100, 0b01000, 0b10011, 0b00011}},
    {U'(', {0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00100, 0b00010}},
    {U')', {0b01000, 0b00100, 0b00010, 0b00010, 0b00010, 0b00100, 0b01000}},
    {U'?', {0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0, 0b00100}},
    {U'³', {0b11100, 0b00100, 0b11100, 0b00100, 0b11100, 0, 0}},
    {U'µ', {0, 0, 0b10001, 0b10001, 0b10011, 0b11101, 0b10000}},
    {U'a', {0, 0, 0b01110, 0b00001, 0b01111, 0b10001, 0b01111}},
    {U'b', {0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b11110}},
    {U'c', {0, 0, 0b01110, 0b10000, 0b10000, 0b10001, 0b01110}},
    {U'd', {0b00001, 0b00001, 0b01101, 0b10011, 0b10001, 0b10001, 0b01111}},
    {U'e', {0, 0, 0b01110, 0b10001, 0b11111, 0b10000, 0b01110}},
    {U'f', {0b00110, 0b01001, 0b01000, 0b11100, 0b01000, 0b01000, 0b01000}},
    {U'g', {0, 0b01111, 0b10001, 0b10001, 0b01111, 0b00001, 0b01110}},
    {U'h', {0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001}},
    {U'i', {0b00100, 0, 0b01100, 0b00100, 0b00100, 0b00100, 0b01110}},
    {U'j', {0b00010, 0, 0b00110, 0b00010, 0b00010, 0b10010, 0b01100}},
    {U'k', {0b10000, 0b10000, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010}},
    {U'l', {0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
    {U'm', {0, 0, 0b11010, 0b10101, 0b10101, 0b10001, 0b10001}},
    {U'n', {0, 0, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001}},
    {U'o', {0, 0, 0b01110, 0b10001, 0b10001, 0b10001, 0b01110}},
    {U'p', {0, 0, 0b11110, 0b10001, 0b11110, 0b10000, 0b10000}},
    {U'q', {0, 0, 0b01101, 0b10011, 0b01111, 0b00001, 0b00001}},
    {U'r', {0, 0, 0b10110, 0b11001, 0b10000, 0b10000, 0b10000}},
    {U's', {0, 0, 0b01110, 0b10000, 0b01110, 0b00001, 0b11110}},
    {U't', {0b01000, 0b01000, 0b11100, 0b01000, 0b01000, 0b01001, 0b00110}},
    {U'u', {0, 0, 0b10001, 0b10001, 0b10001, 0b10011, 0b01101}},
    {U'v', {0, 0, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100}},
    {U'w', {0, 0, 0b10001, 0b10001, 0b10101, 0b10101, 0b01010}},
    {U'x', {0, 0, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001}},
    {U'y', {0, 0, 0b10001, 0b10001, 0b01111, 0b00001, 0b01110}},
    {U'z', {0, 0, 0b11111, 0b00010, 0b00100, 0b01000, 0b11111}},
};

// The code points of UTF-8 `text` (a malformed byte: '?').
std::vector<char32_t> CodePoints(absl::string_view text) {
  std::vector<char32_t> out;
  for (size_t i = 0; i < text.size();) {
    const auto b = static_cast<unsigned char>(text[i]);
    const int n = b < 0x80 ? 1 : (b >> 5) == 6 ? 2 : (b >> 4) == 14 ? 3 : (b >> 3) == 30 ? 4 : 0;
    if (n == 0 || i + n > text.size()) {
      out.push_back(U'?');
      ++i;
      continue;
    }
    char32_t c = n == 1 ? b : b & (0x7f >> n);
    for (int k = 1; k < n; ++k) c = (c << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3f);
    out.push_back(c);
    i += n;
  }
  return out;
}

const Glyph& GlyphOf(char32_t c) {
  if (c >= U'A' && c <= U'Z') c = c - U'A' + U'a';
  if (c == U'μ') c = U'µ';  // the Greek letter and the micro sign look alike
  for (const Glyph& g : kGlyphs) {
    if (g.code == c) return g;
  }
  for (const Glyph& g : kGlyphs) {
    if (g.code == U'?') return g;
  }
  return kGlyphs[0];
}

}  // namespace

int TextWidth(absl::string_view text, int scale) {
  const size_t n = CodePoints(text).size();
  return n == 0 ? 0 : static_cast<int>((n * kGlyphAdvance - 1) * scale);
}

void DrawText(RgbImage* image, int x, int y, absl::string_view text,
              const std::array<uint8_t, 3>& colour, int scale) {
  for (char32_t c : CodePoints(text)) {
    const Glyph& g = GlyphOf(c);
    for (int row = 0; row < kGlyphHeight; ++row) {
      for (int col = 0; col < kGlyphWidth; ++col) {
        if (!(g.rows[row] >> (kGlyphWidth - 1 - col) & 1)) continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx)
            image->Set(x + col * scale + dx, y + row * scale + dy, colour);
      }
    }
    x += kGlyphAdvance * scale;
  }
}

}  // namespace sheetmesh
