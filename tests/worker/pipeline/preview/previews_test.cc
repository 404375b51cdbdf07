#include "worker/pipeline/preview/previews.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <png.h>

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
    mesh.face_thickness.assign(mesh.num_faces(), 3.0f);
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
  ASSERT_EQ(k, 8);  // 512 / 20 is above 8: capped
  EXPECT_EQ(p.image.width, 20 * k);
  EXPECT_EQ(p.image.height, 10 * k);
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
  for (size_t f = 0; f < s.mesh.num_faces(); ++f) s.mesh.face_thickness[f] = 1.0f + f % 7;
  const Preview p = ThicknessPreview(s.mesh);
  EXPECT_EQ(p.fields["faces"], s.mesh.num_faces());
  EXPECT_THAT(p.fields["thickness_range_voxels"].get<std::vector<double>>(),
              ::testing::ElementsAre(1.0, 7.0));
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

}  // namespace
}  // namespace sheetmesh
