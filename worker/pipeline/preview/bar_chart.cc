#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "worker/pipeline/preview/bitmap_font.h"
#include "worker/pipeline/preview/legend.h"
#include "worker/pipeline/preview/previews.h"

namespace sheetmesh {
namespace {

// The series' colours, in order (then repeated).
constexpr std::array<uint8_t, 3> kSeriesColours[] = {
    {74, 123, 208}, {255, 170, 40}, {110, 200, 120}, {220, 90, 90}};
constexpr std::array<uint8_t, 3> kGrid = {70, 76, 88};

void FillRect(RgbImage* im, int x0, int y0, int x1, int y1, const std::array<uint8_t, 3>& c) {
  for (int y = std::max(0, y0); y < std::min(im->height, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(im->width, x1); ++x) im->Set(x, y, c);
}

bool Drawable(double v) { return std::isfinite(v) && v > 0; }

}  // namespace

Preview LogBarPreview(const LogBarChart& chart) {
  Preview p;
  p.file = chart.file;
  double lo = 1e300, hi = -1e300;
  for (const auto& [label, values] : chart.groups)
    for (double v : values)
      if (Drawable(v)) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
  const bool empty = lo > hi;
  // Whole decades around the values.
  const int d_lo = empty ? 0 : static_cast<int>(std::floor(std::log10(lo)));
  const int d_hi = empty ? 1 : std::max(d_lo + 1, static_cast<int>(std::ceil(std::log10(hi))));
  const int ticks_w =
      std::max(TextWidth(absl::StrCat("1e", d_lo)), TextWidth(absl::StrCat("1e", d_hi)));
  const int left = 10 + ticks_w, top = 12 + kGlyphHeight, bottom = 8 + kGlyphHeight;
  const int plot_h = 220, bar_w = 14, gap = 18;
  const int series = std::max<int>(1, static_cast<int>(chart.series.size()));
  const int group_w = series * bar_w + gap;
  const int plot_w = std::max(240, static_cast<int>(chart.groups.size()) * group_w + gap);
  RgbImage& im = p.image;
  im.width = left + plot_w + 10;
  im.height = top + plot_h + bottom;
  im.rgb.resize(3 * static_cast<size_t>(im.width) * im.height);
  FillRect(&im, 0, 0, im.width, im.height, kPreviewBackground);
  DrawText(&im, left, 4, chart.title, kPreviewLegendInk);
  const auto y_of = [&](double v) {
    const double t = (std::log10(v) - d_lo) / (d_hi - d_lo);
    return top + plot_h - static_cast<int>(std::lround(t * plot_h));
  };
  // The decades: a grid line and its label each.
  const int step = std::max(1, (d_hi - d_lo + 7) / 8);
  for (int d = d_lo; d <= d_hi; d += step) {
    const int y = y_of(std::pow(10.0, d));
    FillRect(&im, left, y, left + plot_w, y + 1, kGrid);
    const std::string tick = absl::StrCat("1e", d);
    DrawText(&im, left - 5 - TextWidth(tick), y - kGlyphHeight / 2, tick, kPreviewLegendInk);
  }
  FillRect(&im, left, top, left + 1, top + plot_h + 1, kPreviewLegendInk);
  nlohmann::json groups = nlohmann::json::array();
  for (size_t g = 0; g < chart.groups.size(); ++g) {
    const auto& [label, values] = chart.groups[g];
    const int x0 = left + gap + static_cast<int>(g) * group_w;
    for (size_t s = 0; s < values.size(); ++s) {
      if (!Drawable(values[s])) continue;
      const int x = x0 + static_cast<int>(s) * bar_w;
      FillRect(&im, x, y_of(values[s]), x + bar_w - 2, top + plot_h,
               kSeriesColours[s % std::size(kSeriesColours)]);
    }
    const int centre = x0 + (static_cast<int>(values.size()) * bar_w) / 2;
    DrawText(&im, centre - TextWidth(label) / 2, top + plot_h + 5, label, kPreviewLegendInk);
    nlohmann::json v = nlohmann::json::array();
    for (double x : values) v.push_back(Drawable(x) ? nlohmann::json(x) : nlohmann::json());
    groups.push_back({{"label", label}, {"values", v}});
  }
  std::vector<LegendLine> legend;
  for (size_t s = 0; s < chart.series.size(); ++s) {
    legend.push_back({kSeriesColours[s % std::size(kSeriesColours)], chart.series[s]});
  }
  for (const std::string& line : chart.caption) legend.push_back({std::nullopt, line});
  AppendLegend(&im, legend, kPreviewBackground, kPreviewLegendInk);
  p.fields = {{"kind", chart.kind},
              {"series", chart.series},
              {"groups", groups},
              {"decades", {d_lo, d_hi}},
              {"log_scale", true}};
  if (empty) p.fields["note"] = "no positive value to draw";
  return p;
}

}  // namespace sheetmesh
