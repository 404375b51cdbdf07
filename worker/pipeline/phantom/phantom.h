// Phantom: synthetic rock volumes with rough, intersecting, perforated and fragmented
// sheets of varying aperture plus small specks, at any size, seeded, with a JSON ground
// truth of every sheet's plane, extent and aperture. Written slab by slab.
#ifndef SHEETMESH_WORKER_PIPELINE_PHANTOM_PHANTOM_H_
#define SHEETMESH_WORKER_PIPELINE_PHANTOM_PHANTOM_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/volume/volume_sink.h"

namespace sheetmesh {

struct PhantomOptions {
  Dims dims{256, 256, 256};
  uint64_t seed = 1;
  int num_sheets = 4;                  // sheets, placed so that they cross near the centre
  double aperture_voxels = 5.0;        // mean sheet thickness
  double aperture_variation = 0.35;    // relative amplitude of aperture change along a sheet
  double undulation_voxels = 3.0;      // amplitude of the sheet's large-scale waviness
  double wall_roughness_voxels = 0.8;  // amplitude of each wall's small-scale roughness
  double extent_fraction = 0.45;       // sheet half-extent as a fraction of the box size
  int holes_per_sheet = 2;             // round holes through each sheet
  double hole_radius_fraction = 0.12;  // hole radius, fraction of the sheet's half-extent
  int fragmented_sheets = 1;           // sheets cut into fragments by narrow gaps
  double fragment_gap_voxels = 3.0;    // width of those gaps (below R = 7: detection bridges)
  double min_dip_degrees = 25.0;       // sheets dip between these two
  double max_dip_degrees = 90.0;
  // When in [0, 1]: every sheet's centre at this fraction of the box's height (z), instead
  // of near the middle (a sheet running along a box face: grazing contacts with it).
  double center_z_fraction = -1;
  // Vugs: a lens on each of the first sheets where a thin fracture opens into a body as
  // thick as it is wide (an ellipsoid on the sheet's plane, its radius across the sheet
  // half its radius along it).
  int vugs_per_sheet = 0;
  double vug_radius_voxels = 12.0;  // along the sheet (drawn within 0.8-1.2 of it)
  // A junction of known angle: when > 0, two sheets through the box's centre (num_sheets is
  // 2) meeting at this angle along a line of random direction, the first sheet's normal
  // random too (any orientation); with junction_t the second ends on the first (a T), else
  // they cross (an X). The truth lists the junction line.
  double junction_degrees = 0;
  bool junction_t = false;
  int num_specks = 0;               // small blobs (-1: one per 20^3 voxels of box)
  double speck_radius_voxels = 1.5;
  DType dtype = DType::kUInt8;
  double sheet_value = 255;  // value of sheet voxels
  double speck_value = 255;  // specks share the sheet phase (they are minor objects)
  double background_value = 0;
};

// A round hole in a sheet, in the sheet's (u, v) coordinates.
struct PhantomHole {
  double u = 0, v = 0, radius = 0;
};
// A straight gap cutting a sheet: points with |u cos θ + v sin θ - offset| < width / 2.
struct PhantomGap {
  double angle = 0, offset = 0, width = 0;
};

struct PhantomSheet {
  Vec3 center;               // voxel coordinates
  Vec3 normal;               // unit, z >= 0
  Vec3 u, v;                 // unit in-plane axes
  double half_extent_u = 0;  // elliptical outline: (a/Ru)^2 + (b/Rv)^2 <= 1
  double half_extent_v = 0;
  double aperture_mean = 0;
  double aperture_min = 0;
  double aperture_max = 0;
  double undulation = 0;
  double wall_roughness = 0;
  std::vector<PhantomHole> holes;
  std::vector<PhantomGap> gaps;
  // A T's stem ends on another sheet: only its side a cut_u + b cut_v >= 0 of the line
  // through the centre is kept (has_cut).
  bool has_cut = false;
  double cut_u = 0, cut_v = 0;
  uint64_t voxels = 0;  // filled in by generation
};

// Where two sheets meet: the line through `point` along `direction` (unit), at `degrees`
// between their planes (the acute one); a T's stem ends on the line ("t"), an X crosses it.
struct PhantomJunction {
  Vec3 point;
  Vec3 direction;
  double degrees = 0;
  int sheet_a = 0, sheet_b = 1;
  bool t = false;
};

struct PhantomSpeck {
  Vec3 center;
  double radius = 0;
};

// A vug: the ellipsoid of semi-axes radius_along (on the sheet's plane) and radius_across
// (along its normal) around `center`, on sheet `sheet`.
struct PhantomVug {
  int sheet = 0;
  Vec3 center;
  Vec3 normal;
  double radius_along = 0;
  double radius_across = 0;

  bool Contains(const Vec3& p) const {
    const Vec3 d = p - center;
    const double w = Dot(d, normal);
    const double along2 = Norm2(d) - w * w;
    return along2 / (radius_along * radius_along) + w * w / (radius_across * radius_across) <= 1;
  }
};

// The geometry of a phantom, decided by the options and seed before any voxel is made.
struct PhantomTruth {
  PhantomOptions options;
  std::vector<PhantomSheet> sheets;
  std::vector<PhantomSpeck> specks;
  std::vector<PhantomVug> vugs;
  std::vector<PhantomJunction> junctions;
  uint64_t sheet_voxels = 0;  // voxels of the sheet phase (sheets and specks, overlaps once)
  uint64_t speck_voxels = 0;

  // JSON with every sheet's plane (centre, normal, dip, dip direction), extent, aperture,
  // holes, gaps and voxel count.
  std::string ToJson() const;
};

// The phantom's geometry. kInvalidArgument for non-positive dims or aperture, a negative
// count, or fractions outside (0, 1].
absl::StatusOr<PhantomTruth> PlanPhantom(const PhantomOptions& options);

// Writes the phantom slab by slab into `sink` (whose info must have options.dims and
// options.dtype) and finishes it. Fills the voxel counts of `truth`. kCancelled if asked.
absl::Status GeneratePhantom(PhantomTruth* truth, VolumeSink& sink, const Progress& progress = {});

// The phantom in memory, for tests and small samples.
absl::StatusOr<DenseVolume> GeneratePhantomDense(PhantomTruth* truth);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_PHANTOM_PHANTOM_H_
