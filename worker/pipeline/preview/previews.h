// Previews: PNG pictures of a run for those who cannot open a 3D viewer (the CLI, the
// Python client, CI logs). Three orthogonal slices through the middle of the volume with
// the sheet phase and the mesh's cross-section (its mid-surface and the walls of its
// prisms) drawn over them, and the thickness map of the largest sheet.
#ifndef SHEETMESH_WORKER_PIPELINE_PREVIEW_PREVIEWS_H_
#define SHEETMESH_WORKER_PIPELINE_PREVIEW_PREVIEWS_H_

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "nlohmann/json.hpp"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/preview/rgb_image.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// The colours of the slice previews (RGB).
inline constexpr std::array<uint8_t, 3> kPreviewBackground = {32, 36, 44};
inline constexpr std::array<uint8_t, 3> kPreviewPhase = {120, 190, 255};
inline constexpr std::array<uint8_t, 3> kPreviewMidSurface = {255, 60, 40};
inline constexpr std::array<uint8_t, 3> kPreviewPrismWall = {255, 190, 40};
inline constexpr std::array<uint8_t, 3> kPreviewLegendInk = {225, 228, 235};

// One preview: its file and what its pixels show (the report lists these).
struct Preview {
  std::string file;  // "preview_slice_z.png", "preview_thickness.png"
  RgbImage image;
  nlohmann::json fields;  // kind, axis, index, rows and columns, scale, ...
};

// The slice through the middle of the volume normal to `axis` (0 x, 1 y, 2 z). Pixels are
// square blocks of `scale` voxels' width (scale ≥ 1 for volumes up to 1024 across, below
// 1 beyond, the nearest voxel taken); the slice of x or y has z upwards. Phase voxels in
// kPreviewPhase, the rest kPreviewBackground, the mesh's mid-surface and prism walls
// drawn over them. Below the slice (the picture widened where it needs), a legend: each
// colour's meaning, the slice's place and the voxel's size in `placement`'s unit.
Preview SlicePreview(const VoxelSet& phase, const TriangleMesh& mesh, int axis,
                     const Placement& placement = {});

// The largest sheet (the faces joined across edges of two faces of one piece, the group of
// largest area) seen along its mean normal, each triangle filled with the colour of its
// aperture (its thickness where the mesh has no aperture; blue thin to yellow thick), a colour
// bar along the bottom labelled with its ends in `placement`'s unit. Empty mesh: a blank
// picture saying so in fields.
Preview ThicknessPreview(const TriangleMesh& mesh, const Placement& placement = {});

// A bar chart on a log scale (for the permeability: the tensor's diagonal, the
// permeameters and the image's reference per axis, then the principal values): `groups`
// along the bottom, each a bar per series (a value that is not positive and finite: no bar),
// a grid line at each decade labelled 1eN, below it a legend of the series' colours and the
// `caption` lines. fields: kind, series, groups (label and values), decades.
struct LogBarChart {
  std::string file;   // "preview_permeability.png"
  std::string kind;   // "permeability"
  std::string title;  // above the plot
  std::vector<std::string> series;
  std::vector<std::pair<std::string, std::vector<double>>> groups;
  std::vector<std::string> caption;
};
Preview LogBarPreview(const LogBarChart& chart);

// The PNG encoding of `image` (8-bit RGB).
absl::StatusOr<std::string> EncodePng(const RgbImage& image);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_PREVIEW_PREVIEWS_H_
