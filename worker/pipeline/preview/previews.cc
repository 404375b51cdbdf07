#include "worker/pipeline/preview/previews.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/preview/bitmap_font.h"
#include "worker/pipeline/preview/legend.h"

namespace sheetmesh {
namespace {

constexpr const char* kAxisName[3] = {"x", "y", "z"};

// How a slice maps voxels to pixels.
struct SliceFrame {
  int axis, cols_axis, rows_axis;
  int64_t index, ncols, nrows;
  bool z_up;     // rows run from the top z down
  double scale;  // pixels per voxel

  int width() const { return std::max(1, static_cast<int>(std::lround(ncols * scale))); }
  int height() const { return std::max(1, static_cast<int>(std::lround(nrows * scale))); }
  // Pixel coordinates of a point in voxel coordinates (voxel centres on integers).
  double Px(const Vec3& p) const { return (p[cols_axis] + 0.5) * scale; }
  double Py(const Vec3& p) const {
    const double r = z_up ? (nrows - 1 - p[rows_axis]) : p[rows_axis];
    return (r + 0.5) * scale;
  }
};

SliceFrame FrameOf(const Dims& dims, int axis) {
  const int64_t n[3] = {dims.nx, dims.ny, dims.nz};
  SliceFrame f;
  f.axis = axis;
  f.cols_axis = axis == 0 ? 1 : 0;
  f.rows_axis = axis == 2 ? 1 : 2;
  f.z_up = axis != 2;
  f.index = n[axis] / 2;
  f.ncols = n[f.cols_axis];
  f.nrows = n[f.rows_axis];
  const int64_t longest = std::max<int64_t>(1, std::max(f.ncols, f.nrows));
  f.scale = longest <= 1024 ? std::clamp<double>(std::floor(512.0 / longest), 1, 8)
                            : 1024.0 / static_cast<double>(longest);
  return f;
}

void DrawLine(RgbImage* im, double x0, double y0, double x1, double y1,
              const std::array<uint8_t, 3>& c) {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int steps = std::max(1, static_cast<int>(std::ceil(2 * len)));
  for (int i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    im->Set(static_cast<int>(std::floor(x0 + t * (x1 - x0))),
            static_cast<int>(std::floor(y0 + t * (y1 - y0))), c);
  }
}

// Where triangle t crosses the plane p[axis] = at: a segment, or false.
bool CutTriangle(const Triangle& t, int axis, double at, Vec3* a, Vec3* b) {
  Vec3 hits[3];
  int n = 0;
  for (int k = 0; k < 3 && n < 2; ++k) {
    const Vec3 &p = t[k], &q = t[(k + 1) % 3];
    const double dp = p[axis] - at, dq = q[axis] - at;
    if ((dp <= 0 && dq > 0) || (dq <= 0 && dp > 0)) {
      const double s = dp / (dp - dq);
      hits[n++] = p + (q - p) * s;
    }
  }
  if (n < 2) return false;
  *a = hits[0];
  *b = hits[1];
  return true;
}

// Blue (thin) through green to yellow (thick), t in [0, 1].
std::array<uint8_t, 3> Ramp(double t) {
  static constexpr double stops[4][3] = {
      {48, 18, 160}, {32, 120, 200}, {40, 190, 120}, {250, 220, 40}};
  t = std::clamp(t, 0.0, 1.0) * 3;
  const int i = std::min(2, static_cast<int>(t));
  const double f = t - i;
  std::array<uint8_t, 3> c;
  for (int k = 0; k < 3; ++k) {
    c[k] = static_cast<uint8_t>(std::lround(stops[i][k] + f * (stops[i + 1][k] - stops[i][k])));
  }
  return c;
}

// Faces grouped across edges of exactly two faces of one piece; the group of largest area.
std::vector<size_t> LargestSheet(const TriangleMesh& mesh) {
  const size_t n = mesh.num_faces();
  std::vector<std::pair<uint64_t, uint32_t>> edges;  // (edge, face)
  edges.reserve(3 * n);
  for (size_t f = 0; f < n; ++f) {
    for (int k = 0; k < 3; ++k) {
      edges.push_back({EdgeKey(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3]), uint32_t(f)});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<uint32_t> root(n);
  for (size_t f = 0; f < n; ++f) root[f] = static_cast<uint32_t>(f);
  auto find = [&](uint32_t f) {
    while (root[f] != f) f = root[f] = root[root[f]];
    return f;
  };
  const bool pieces = mesh.face_piece.size() == n;
  for (size_t i = 0; i + 1 < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    const uint32_t a = edges[i].second, b = edges[i + 1].second;
    if (j - i == 2 && (!pieces || mesh.face_piece[a] == mesh.face_piece[b])) {
      root[find(a)] = find(b);
    }
    i = j;
  }
  std::vector<double> area(n, 0.0);
  for (size_t f = 0; f < n; ++f) area[find(static_cast<uint32_t>(f))] += Area(Corners(mesh, f));
  size_t best = 0;
  for (size_t f = 1; f < n; ++f) best = area[f] > area[best] ? f : best;
  std::vector<size_t> out;
  for (size_t f = 0; f < n; ++f)
    if (n > 0 && find(static_cast<uint32_t>(f)) == best) out.push_back(f);
  return out;
}

// A length given in voxels, in the volume's unit: "0.0123 mm"; "2.5 voxels" where the
// volume has no physical size.
std::string LengthText(double voxels, const Placement& placement) {
  if (placement.unit.empty()) {
    const bool unit_voxels = placement.spacing == Vec3{1, 1, 1};
    return absl::StrFormat("%.3g%s", unit_voxels ? voxels : PhysicalLength(voxels, placement),
                           unit_voxels ? " voxels" : "");
  }
  return absl::StrFormat("%.3g %s", PhysicalLength(voxels, placement), placement.unit);
}

void PngToString(png_structp png, png_bytep data, png_size_t n) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), n);
}

void PngError(png_structp png, png_const_charp msg) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = msg;
  png_longjmp(png, 1);
}

}  // namespace

void AppendLegend(RgbImage* im, const std::vector<LegendLine>& lines,
                  const std::array<uint8_t, 3>& background, const std::array<uint8_t, 3>& ink) {
  constexpr int kMargin = 6, kLine = kGlyphHeight + 5, kSwatch = kGlyphHeight + 1;
  int width = im->width;
  for (const LegendLine& l : lines) {
    width = std::max(width, 2 * kMargin + (l.swatch ? kSwatch + 5 : 0) + TextWidth(l.text));
  }
  RgbImage out;
  out.width = width;
  out.height = im->height + 2 * kMargin + kLine * static_cast<int>(lines.size());
  out.rgb.resize(3 * static_cast<size_t>(out.width) * out.height);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) out.Set(x, y, background);
  for (int y = 0; y < im->height; ++y) {
    std::copy_n(&im->rgb[3 * static_cast<size_t>(y) * im->width], 3 * im->width,
                &out.rgb[3 * static_cast<size_t>(y) * out.width]);
  }
  int y = im->height + kMargin;
  for (const LegendLine& l : lines) {
    int x = kMargin;
    if (l.swatch) {
      for (int dy = 0; dy < kSwatch; ++dy)
        for (int dx = 0; dx < kSwatch; ++dx) out.Set(x + dx, y + dy - 1, *l.swatch);
      x += kSwatch + 5;
    }
    DrawText(&out, x, y, l.text, ink);
    y += kLine;
  }
  *im = std::move(out);
}

Preview SlicePreview(const VoxelSet& phase, const TriangleMesh& mesh, int axis,
                     const Placement& placement) {
  const SliceFrame f = FrameOf(phase.dims(), axis);
  Preview p;
  p.file = absl::StrCat("preview_slice_", kAxisName[axis], ".png");
  RgbImage& im = p.image;
  im.width = f.width();
  im.height = f.height();
  im.rgb.resize(3 * static_cast<size_t>(im.width) * im.height);
  // The slice's phase as a voxel grid, then scaled.
  std::vector<uint8_t> in(static_cast<size_t>(f.ncols * f.nrows), 0);
  auto mark = [&](int64_t col, int64_t row) { in[row * f.ncols + col] = 1; };
  const Dims& d = phase.dims();
  if (axis == 2 || axis == 1) {
    for (int64_t other = 0; other < (axis == 2 ? d.ny : d.nz); ++other) {
      const int64_t y = axis == 2 ? other : f.index, z = axis == 2 ? f.index : other;
      for (const Run& r : phase.RowRuns(y, z)) {
        for (int64_t x = r.x0; x < r.x1; ++x) mark(x, other);
      }
    }
  } else {
    for (int64_t z = 0; z < d.nz; ++z)
      for (int64_t y = 0; y < d.ny; ++y)
        if (phase.Contains(f.index, y, z)) mark(y, z);
  }
  for (int py = 0; py < im.height; ++py) {
    const int64_t r = std::min<int64_t>(f.nrows - 1, static_cast<int64_t>(py / f.scale));
    const int64_t row = f.z_up ? f.nrows - 1 - r : r;
    for (int px = 0; px < im.width; ++px) {
      const int64_t col = std::min<int64_t>(f.ncols - 1, static_cast<int64_t>(px / f.scale));
      im.Set(px, py, in[row * f.ncols + col] ? kPreviewPhase : kPreviewBackground);
    }
  }
  // The prisms' walls, then the mid-surface over them.
  const bool thick = mesh.face_thickness_voxels.size() == mesh.num_faces();
  size_t cut = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (size_t t = 0; t < mesh.num_faces(); ++t) {
      const Triangle tri = Corners(mesh, t);
      Vec3 a, b;
      if (pass == 0) {
        if (!thick) continue;
        const Vec3 n = UnitNormal(tri) * (0.5 * mesh.face_thickness_voxels[t]);
        for (double side : {-1.0, 1.0}) {
          const Triangle moved = {tri[0] + n * side, tri[1] + n * side, tri[2] + n * side};
          if (CutTriangle(moved, axis, static_cast<double>(f.index), &a, &b)) {
            DrawLine(&im, f.Px(a), f.Py(a), f.Px(b), f.Py(b), kPreviewPrismWall);
          }
        }
      } else if (CutTriangle(tri, axis, static_cast<double>(f.index), &a, &b)) {
        DrawLine(&im, f.Px(a), f.Py(a), f.Px(b), f.Py(b), kPreviewMidSurface);
        ++cut;
      }
    }
  }
  const int64_t extent[3] = {phase.dims().nx, phase.dims().ny, phase.dims().nz};
  const int slice_height = im.height;
  AppendLegend(&im,
               {{kPreviewPhase, "sheet phase"},
                {kPreviewMidSurface, "mesh: mid-surface"},
                {kPreviewPrismWall, "mesh: prism walls (thickness)"},
                {std::nullopt, absl::StrFormat("%s = %d of %d; %s across, %s %s", kAxisName[axis],
                                               f.index, extent[axis], kAxisName[f.cols_axis],
                                               kAxisName[f.rows_axis], f.z_up ? "up" : "down")},
                {std::nullopt, absl::StrCat("1 voxel = ", LengthText(1, placement))}},
               kPreviewBackground, kPreviewLegendInk);
  p.fields = {{"kind", "slice"},
              {"axis", kAxisName[axis]},
              {"slice_height", slice_height},
              {"index", f.index},
              {"columns", kAxisName[f.cols_axis]},
              {"rows", kAxisName[f.rows_axis]},
              {"rows_upward", f.z_up},
              {"pixels_per_voxel", f.scale},
              {"cut_triangles", cut},
              {"colours",
               {{"phase", kPreviewPhase},
                {"background", kPreviewBackground},
                {"mid_surface", kPreviewMidSurface},
                {"prism_wall", kPreviewPrismWall}}}};
  return p;
}

Preview ThicknessPreview(const TriangleMesh& mesh, const Placement& placement) {
  Preview p;
  p.file = "preview_thickness.png";
  // The largest sheet: faces joined across edges of exactly two faces of one piece (a
  // junction, where three or more meet, or a seam between pieces separates sheets), the
  // group of largest area.
  std::vector<size_t> faces = LargestSheet(mesh);
  const int32_t piece =
      faces.empty() || mesh.face_piece.size() != mesh.num_faces() ? -1 : mesh.face_piece[faces[0]];
  // The aperture a flow model takes, where the mesh has one; else the thickness.
  const bool aperture = mesh.face_aperture_voxels.size() == mesh.num_faces();
  const std::vector<float>& values =
      aperture ? mesh.face_aperture_voxels : mesh.face_thickness_voxels;
  const bool thick = values.size() == mesh.num_faces();
  RgbImage& im = p.image;
  if (faces.empty()) {
    im.width = im.height = 64;
    im.rgb.assign(3 * 64 * 64, 255);
    p.fields = {{"kind", "thickness"}, {"faces", 0}, {"note", "the mesh has no triangles"}};
    return p;
  }
  // The mean normal (faces turned to agree), and a frame in the sheet's plane.
  Vec3 n{0, 0, 0};
  for (size_t t : faces) {
    const Vec3 a = AreaVector(Corners(mesh, t));
    n += Dot(a, n) < 0 ? -a : a;
  }
  n = Normalized(n);
  if (Norm2(n) == 0) n = {0, 0, 1};
  const Vec3 helper = std::abs(n.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 u = Normalized(Cross(n, helper)), v = Cross(n, u);
  double lo_u = 1e300, hi_u = -1e300, lo_v = 1e300, hi_v = -1e300, lo_t = 1e300, hi_t = -1e300;
  for (size_t t : faces) {
    for (const Vec3& q : Corners(mesh, t)) {
      lo_u = std::min(lo_u, Dot(q, u)), hi_u = std::max(hi_u, Dot(q, u));
      lo_v = std::min(lo_v, Dot(q, v)), hi_v = std::max(hi_v, Dot(q, v));
    }
  }
  // Colours over the 2nd to 98th percentile of the faces' thickness (a few slivers at a
  // junction would wash the map out otherwise); the full range is reported too.
  std::vector<double> ths;
  for (size_t t : faces) ths.push_back(thick ? values[t] : 1.0);
  std::sort(ths.begin(), ths.end());
  lo_t = ths[static_cast<size_t>(0.02 * (ths.size() - 1))];
  hi_t = ths[static_cast<size_t>(0.98 * (ths.size() - 1))];
  const int margin = 8, bar = 16, side = 512;
  const double span = std::max({hi_u - lo_u, hi_v - lo_v, 1e-9});
  const double s = (side - 2 * margin) / span;
  im.width = static_cast<int>(std::ceil((hi_u - lo_u) * s)) + 2 * margin;
  im.height = static_cast<int>(std::ceil((hi_v - lo_v) * s)) + 2 * margin + bar + margin;
  im.rgb.assign(3 * static_cast<size_t>(im.width) * im.height, 255);
  auto at = [&](const Vec3& q) {
    return std::array<double, 2>{margin + (Dot(q, u) - lo_u) * s, margin + (hi_v - Dot(q, v)) * s};
  };
  for (size_t t : faces) {
    const Triangle tri = Corners(mesh, t);
    const auto a = at(tri[0]), b = at(tri[1]), c = at(tri[2]);
    const double area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if (area == 0) continue;
    const double th = thick ? values[t] : 1.0;
    const auto colour = Ramp(hi_t > lo_t ? (th - lo_t) / (hi_t - lo_t) : 0.5);
    const int x0 = static_cast<int>(std::floor(std::min({a[0], b[0], c[0]})));
    const int x1 = static_cast<int>(std::ceil(std::max({a[0], b[0], c[0]})));
    const int y0 = static_cast<int>(std::floor(std::min({a[1], b[1], c[1]})));
    const int y1 = static_cast<int>(std::ceil(std::max({a[1], b[1], c[1]})));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = (b[0] - px) * (c[1] - py) - (c[0] - px) * (b[1] - py);
        const double w1 = (c[0] - px) * (a[1] - py) - (a[0] - px) * (c[1] - py);
        const double w2 = (a[0] - px) * (b[1] - py) - (b[0] - px) * (a[1] - py);
        if ((w0 >= 0 && w1 >= 0 && w2 >= 0) || (w0 <= 0 && w1 <= 0 && w2 <= 0)) {
          im.Set(x, y, colour);
        }
      }
    }
  }
  // The colour bar: thin on the left, thick on the right.
  const int bar_top = im.height - margin - bar;
  for (int x = margin; x < im.width - margin; ++x) {
    const auto c = Ramp(static_cast<double>(x - margin) / std::max(1, im.width - 2 * margin - 1));
    for (int y = bar_top; y < bar_top + bar; ++y) im.Set(x, y, c);
  }
  const char* what = aperture ? "aperture" : "thickness";
  AppendLegend(
      &im,
      {{std::nullopt, absl::StrFormat("%s of piece %d, %s to %s", what, piece,
                                      LengthText(lo_t, placement), LengthText(hi_t, placement))},
       {std::nullopt, "(colours: 2nd to 98th percentile, thin left, thick right)"}},
      {255, 255, 255}, {40, 40, 40});
  p.fields = {{"kind", "thickness"},
              {"field", what},
              {"piece", piece},
              {"faces", faces.size()},
              {"normal", {n.x, n.y, n.z}},
              {"thickness_range_voxels", {ths.front(), ths.back()}},
              {"colour_range_voxels", {lo_t, hi_t}},
              {"pixels_per_voxel", s},
              {"colour_bar", "bottom: thin (left) to thick (right)"}};
  return p;
}

absl::StatusOr<std::string> EncodePng(const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * static_cast<size_t>(image.width) * image.height) {
    return absl::InternalError("an empty or inconsistent picture");
  }
  std::string out, error;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, PngError, nullptr);
  if (png == nullptr) return absl::ResourceExhaustedError("libpng: no memory");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return absl::InternalError(absl::StrCat("libpng: ", error));
  }
  png_set_write_fn(png, &out, PngToString, nullptr);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) {
    png_write_row(png, const_cast<png_bytep>(&image.rgb[3 * static_cast<size_t>(y) * image.width]));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

}  // namespace sheetmesh
