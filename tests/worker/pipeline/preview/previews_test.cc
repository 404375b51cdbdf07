#include "worker/pipeline/preview/previews.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <png.h>

#include <set>

#include "tests/testing/meshes.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::Grid;

// A slab z = 4..6 over x, y in [2, 18) of a 20 x 20 x 10 box, and its mid-surface z = 5
// meshed as a grid carrying thickness 3.
struct Slab {
  VoxelSet phase;
  TriangleMesh mesh;
  Slab() {
    VoxelSet::Builder b(Dims{20, 20, 10});
    for (int64_t z = 4; z <= 6; ++z)
      for (int64_t y = 2; y < 18; ++y) b.AddRun(y, z, 2, 18);
    phase = std::move(b).Build();
    mesh = Grid(15, 15, [](int x, int y) { return Vec3{2.0 + x, 2.0 + y, 5.0}; });
    mesh.face_thickness_voxels.assign(mesh.num_faces(), 3.0f);
  }
};

std::array<uint8_t, 3> Pixel(const RgbImage& im, int x, int y) {
  const uint8_t* p = &im.rgb[3 * (static_cast<size_t>(y) * im.width + x)];
  return {p[0], p[1], p[2]};
}

TEST(PreviewsTest, SliceAcrossASlabShowsItsPhaseAndItsPrism) {
  const Slab s;
  const Preview p = SlicePreview(s.phase, s.mesh, /*axis=*/0);  // x = 10: columns y, rows z
  EXPECT_EQ(p.file, "preview_slice_x.png");
  EXPECT_EQ(p.fields["index"], 10);
  const int k = p.fields["pixels_per_voxel"].get<int>();
  ASSERT_EQ(k, 8);                   // 512 / 20 is above 8: capped
  EXPECT_GE(p.image.width, 20 * k);  // wider where the legend needs
  EXPECT_EQ(p.fields["slice_height"], 10 * k);
  EXPECT_GT(p.image.height, 10 * k);  // the legend below
  // Row of voxel z (z up): the top row is z = 9.
  auto at = [&](int y, int z) { return Pixel(p.image, y * k + 1, (9 - z) * k + 1); };
  EXPECT_EQ(at(0, 5), kPreviewBackground);
  EXPECT_EQ(at(10, 9), kPreviewBackground);
  EXPECT_EQ(at(10, 4), kPreviewPhase);
  EXPECT_EQ(at(10, 6), kPreviewPhase);
  // The mid-surface z = 5 is drawn through the middle of its voxel row, the walls at
  // z = 3.5 and 6.5, on the edges of the phase.
  EXPECT_EQ(Pixel(p.image, 10 * k + 3, (9 - 5) * k + k / 2), kPreviewMidSurface);
  EXPECT_EQ(Pixel(p.image, 10 * k + 3, static_cast<int>((9 - 6.5 + 0.5) * k)), kPreviewPrismWall);
  EXPECT_GT(p.fields["cut_triangles"].get<int>(), 0);
}

TEST(PreviewsTest, TheSliceSaysWhatItsColoursMeanAndHowLargeAVoxelIs) {
  const Slab s;
  Placement mm;
  mm.spacing = {0.005, 0.005, 0.005};
  mm.unit = "mm";
  const Preview p = SlicePreview(s.phase, s.mesh, /*axis=*/0, mm);
  const int top = p.fields["slice_height"].get<int>();
  // Below the slice, a swatch of each colour the slice uses, then text in the legend's ink.
  std::set<std::array<uint8_t, 3>> below;
  for (int y = top; y < p.image.height; ++y)
    for (int x = 0; x < p.image.width; ++x) below.insert(Pixel(p.image, x, y));
  for (const auto& c : {kPreviewPhase, kPreviewMidSurface, kPreviewPrismWall, kPreviewLegendInk})
    EXPECT_TRUE(below.count(c)) << int(c[0]) << "," << int(c[1]) << "," << int(c[2]);
  // The last line reads "1 voxel = 0.005 mm": as wide as that text, drawn in ink.
  const Preview in_voxels = SlicePreview(s.phase, s.mesh, /*axis=*/0);
  EXPECT_NE(p.image.rgb, in_voxels.image.rgb) << "the voxel's size is in the legend";
}

TEST(PreviewsTest, SliceAlongTheSlabIsAllPhaseInsideItsOutline) {
  const Slab s;
  const Preview p = SlicePreview(s.phase, s.mesh, /*axis=*/2);  // z = 5: the mid-surface
  const int k = p.fields["pixels_per_voxel"].get<int>();
  EXPECT_EQ(p.fields["rows_upward"], false);
  EXPECT_EQ(Pixel(p.image, 3 * k + 2, 15 * k + 2), kPreviewPhase);
  EXPECT_EQ(Pixel(p.image, 19 * k + 2, 15 * k + 2), kPreviewBackground);
  EXPECT_EQ(p.fields["cut_triangles"], 0);  // the plane lies in the slice, not across it
}

TEST(PreviewsTest, ThicknessMapColoursByThicknessAndEncodesAsPng) {
  Slab s;
  for (size_t f = 0; f < s.mesh.num_faces(); ++f) s.mesh.face_thickness_voxels[f] = 1.0f + f % 7;
  const Preview p = ThicknessPreview(s.mesh);
  EXPECT_EQ(p.fields["faces"], s.mesh.num_faces());
  EXPECT_THAT(p.fields["thickness_range_voxels"].get<std::vector<double>>(),
              ::testing::ElementsAre(1.0, 7.0));
  EXPECT_EQ(p.fields["field"], "thickness");
  // With apertures, the map is of them.
  s.mesh.face_aperture_voxels.assign(s.mesh.num_faces(), 2.0f);
  s.mesh.face_aperture_voxels[0] = 4.0f;
  const Preview a = ThicknessPreview(s.mesh);
  EXPECT_EQ(a.fields["field"], "aperture");
  EXPECT_THAT(a.fields["thickness_range_voxels"].get<std::vector<double>>(),
              ::testing::ElementsAre(2.0, 4.0));
  absl::StatusOr<std::string> png = EncodePng(p.image);
  ASSERT_TRUE(png.ok()) << png.status();
  // Decode it again with libpng: the size and a pixel survive.
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_memory(&img, png->data(), png->size()));
  img.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> rgb(PNG_IMAGE_SIZE(img));
  ASSERT_TRUE(png_image_finish_read(&img, nullptr, rgb.data(), 0, nullptr));
  EXPECT_EQ(static_cast<int>(img.width), p.image.width);
  EXPECT_EQ(static_cast<int>(img.height), p.image.height);
  EXPECT_EQ(rgb, p.image.rgb);
}

TEST(PreviewsTest, AnEmptyMeshGivesABlankThicknessMapNotAnError) {
  const Preview p = ThicknessPreview(TriangleMesh{});
  EXPECT_EQ(p.fields["faces"], 0);
  EXPECT_TRUE(EncodePng(p.image).ok());
}

// The log-scale bars: a bar's top rises with the log of its value, one decade per equal
// height; a value that is not positive draws no bar; the fields list what is drawn.
TEST(PreviewsTest, LogBarsRiseWithTheLogOfTheirValues) {
  LogBarChart c;
  c.file = "preview_permeability.png";
  c.kind = "permeability";
  c.title = "permeability in darcy, log scale";
  c.series = {"tensor", "permeameter"};
  c.groups = {{"x", {1e-3, 1e-5}}, {"y", {1e-1, 0}}, {"z", {1e-4, 1e-4}}};
  const Preview p = LogBarPreview(c);
  EXPECT_EQ(p.fields["decades"], nlohmann::json({-5, -1}));
  EXPECT_TRUE(p.fields["groups"][1]["values"][1].is_null());
  // Each bar's height in pixels of its series' colour, scanning its column from the bottom.
  const std::array<uint8_t, 3> tensor = {74, 123, 208};  // the first series' colour
  std::vector<int> heights;
  for (int x = 0; x < p.image.width; ++x) {
    int n = 0;
    for (int y = 0; y < p.image.height; ++y) n += Pixel(p.image, x, y) == tensor;
    if (n > 0 && (heights.empty() || n != heights.back())) heights.push_back(n);
  }
  // The swatch in the legend is a small square; the three bars are the tall columns, in order
  // x (1e-3), y (1e-1), z (1e-4): 2, 4 and 1 decades above the floor of 1e-5.
  std::vector<int> bars;
  for (int h : heights)
    if (h > 20) bars.push_back(h);
  ASSERT_EQ(bars.size(), 3u);
  EXPECT_NEAR(bars[0], 2 * bars[2], 2);
  EXPECT_NEAR(bars[1], 4 * bars[2], 2);
  EXPECT_TRUE(EncodePng(p.image).ok());
}

}  // namespace
}  // namespace sheetmesh
