#include "worker/pipeline/phantom/phantom_presets.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace sheetmesh {
namespace {

PhantomOptions Sample() {
  PhantomOptions o;
  o.dims = {128, 112, 96};
  o.seed = 7;
  o.num_sheets = 3;
  o.aperture_voxels = 4.0;
  o.undulation_voxels = 2.0;
  o.extent_fraction = 0.42;
  o.holes_per_sheet = 1;
  o.fragmented_sheets = 1;
  o.num_specks = 40;
  return o;
}

PhantomOptions Paper() {
  PhantomOptions o;
  o.dims = {1012, 1024, 931};
  o.num_sheets = 6;
  o.num_specks = -1;
  return o;
}

PhantomOptions ThickSlab() {
  PhantomOptions o;
  o.dims = {100, 100, 111};
  o.seed = 3;
  o.num_sheets = 1;
  o.aperture_voxels = 40.0;
  o.aperture_variation = 0.25;  // 30-50 voxels along the slab
  o.undulation_voxels = 2.0;
  o.wall_roughness_voxels = 4.0;
  o.extent_fraction = 1.0;  // beyond the box: the slab crosses it
  o.holes_per_sheet = 0;
  o.fragmented_sheets = 0;
  o.min_dip_degrees = 0.0;
  o.max_dip_degrees = 5.0;
  o.num_specks = 0;
  return o;
}

PhantomOptions RoughNetwork() {
  PhantomOptions o;
  o.dims = {160, 160, 160};
  o.seed = 11;
  o.num_sheets = 4;
  o.aperture_voxels = 5.0;
  o.aperture_variation = 0.35;
  o.undulation_voxels = 3.0;
  o.wall_roughness_voxels = 1.5;
  o.extent_fraction = 0.28;  // half-extents 36-54 voxels
  o.holes_per_sheet = 2;
  o.hole_radius_fraction = 0.15;
  o.fragmented_sheets = 0;
  o.num_specks = 200;
  return o;
}

// As hard as a real dissolution slab: walls rough and not parallel, the aperture 20-60
// voxels along it, dipping up to 15 degrees.
PhantomOptions RoughSlab() {
  PhantomOptions o = ThickSlab();
  o.seed = 5;
  o.aperture_voxels = 40.0;
  o.aperture_variation = 0.5;  // 20-60 voxels
  o.undulation_voxels = 4.0;
  o.wall_roughness_voxels = 6.0;
  o.max_dip_degrees = 15.0;
  return o;
}

// A dense network of thin sheets crossing at shallow angles: dips within 2-10 degrees, so
// that any two meet at 20 degrees or less.
PhantomOptions ShallowNetwork() {
  PhantomOptions o;
  o.dims = {160, 160, 120};
  o.seed = 13;
  o.num_sheets = 6;
  o.aperture_voxels = 3.0;
  o.aperture_variation = 0.3;
  o.undulation_voxels = 1.5;
  o.wall_roughness_voxels = 1.0;
  o.extent_fraction = 0.35;
  o.holes_per_sheet = 1;
  o.fragmented_sheets = 0;
  o.min_dip_degrees = 2.0;
  o.max_dip_degrees = 10.0;
  o.num_specks = 60;
  return o;
}

// Sheets running along the box's bottom face, a few voxels above it and dipping 1-6
// degrees: they meet the face at grazing angles.
PhantomOptions GrazingSheet() {
  PhantomOptions o;
  o.dims = {140, 120, 80};
  o.seed = 17;
  o.num_sheets = 2;
  o.aperture_voxels = 4.0;
  o.aperture_variation = 0.3;
  o.undulation_voxels = 1.5;
  o.wall_roughness_voxels = 1.0;
  o.extent_fraction = 0.6;
  o.holes_per_sheet = 1;
  o.fragmented_sheets = 0;
  o.min_dip_degrees = 1.0;
  o.max_dip_degrees = 6.0;
  o.center_z_fraction = 0.07;
  o.num_specks = 20;
  return o;
}

// A network of thin sheets each opening into a vug (a lens 20-30 voxels across, half as
// thick): pieces that are sheets where thin and bodies where thick.
PhantomOptions VuggyNetwork() {
  PhantomOptions o = RoughNetwork();
  o.seed = 19;
  o.aperture_voxels = 3.0;
  o.holes_per_sheet = 1;
  o.vugs_per_sheet = 1;
  o.vug_radius_voxels = 12.0;
  o.num_specks = 60;
  return o;
}

// Two plain planar sheets, 3 voxels thick, crossing at 30 degrees through the box's centre
// along a line of random direction: the junction's known answer (--junction_degrees sets
// the angle, --junction=t ends one on the other).
PhantomOptions Crossing() {
  PhantomOptions o;
  o.dims = {112, 112, 112};
  o.seed = 23;
  o.num_sheets = 2;
  o.junction_degrees = 30;
  o.aperture_voxels = 3.0;
  o.aperture_variation = 0;
  o.undulation_voxels = 0;
  o.wall_roughness_voxels = 0;
  o.extent_fraction = 1.0;  // across the box: the sheets end on its faces
  o.holes_per_sheet = 0;
  o.fragmented_sheets = 0;
  o.num_specks = 0;
  return o;
}

// A T: a sheet ending on another at 60 degrees.
PhantomOptions TJunction() {
  PhantomOptions o = Crossing();
  o.seed = 29;
  o.junction_degrees = 60;
  o.junction_t = true;
  return o;
}

// As a real scan's junction: rough walls that are not parallel, the aperture varying 2-6
// voxels, a gentle waviness, a hole, specks, crossing at 20 degrees.
PhantomOptions RoughCrossing() {
  PhantomOptions o = Crossing();
  o.dims = {128, 128, 128};
  o.seed = 31;
  o.junction_degrees = 20;
  o.aperture_voxels = 4.0;
  o.aperture_variation = 0.4;
  o.undulation_voxels = 1.5;
  o.wall_roughness_voxels = 1.0;
  o.holes_per_sheet = 1;
  o.num_specks = 20;
  return o;
}

}  // namespace

std::vector<std::string> PhantomPresetNames() {
  return {"sample",        "paper",         "thick_slab", "rough_network",  "rough_slab",
          "shallow_network", "grazing_sheet", "vuggy_network", "crossing", "t_junction",
          "rough_crossing"};
}

absl::StatusOr<PhantomOptions> PhantomPreset(std::string_view name) {
  if (name == "sample") return Sample();
  if (name == "paper") return Paper();
  if (name == "thick_slab") return ThickSlab();
  if (name == "rough_network") return RoughNetwork();
  if (name == "rough_slab") return RoughSlab();
  if (name == "shallow_network") return ShallowNetwork();
  if (name == "grazing_sheet") return GrazingSheet();
  if (name == "vuggy_network") return VuggyNetwork();
  if (name == "crossing") return Crossing();
  if (name == "t_junction") return TJunction();
  if (name == "rough_crossing") return RoughCrossing();
  return absl::InvalidArgumentError(
      absl::StrCat("--preset=", absl::string_view(name.data(), name.size()), " is not known; use ",
                   absl::StrJoin(PhantomPresetNames(), ", ")));
}

}  // namespace sheetmesh
