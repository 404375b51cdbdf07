// The parameter table's rows for the volume mesh, the flow on it and the files written
// (the rest of the table: parameter_table.cc).
#include "worker/pipeline/run/parameter_row_helpers.h"

namespace sheetmesh::parameter_rows {

std::vector<ParamRow> VolumeMeshRows() {
  std::vector<ParamRow> rows;
  rows.push_back(Bool("volume_mesh", SM_MEMBER(volume_mesh),
                      "also tetrahedralize the box with the sheets as internal faces (TetGen)"));
  rows.push_back(Integer("max_tetrahedra", SM_MEMBER(volume.max_tetrahedra), "[0, 1e12]", "",
                         "at most this many tetrahedra: the lattice coarsens, the improvement "
                         "stops inserting (0: no bound)"));
  rows.push_back(Number("tet.radius_edge_ratio", SM_MEMBER(volume.tetgen.max_radius_edge_ratio),
                        "0 | [1, 10]", "", "TetGen's radius-edge ratio bound (-q; 0: none)"));
  rows.push_back(Number("tet.min_dihedral", SM_MEMBER(volume.tetgen.min_dihedral_degrees),
                        "[0, 20]", "degrees",
                        "the smallest dihedral angle asked of TetGen (above about 20 degrees "
                        "its refinement need not end)"));
  rows.push_back(Number("tet.max_volume", SM_MEMBER(volume.tetgen.max_volume), "[0, 1e30]",
                        "unit^3", "largest tetrahedron volume (0: none)"));
  rows.push_back(Bool("tet.steiner_on_sheets", SM_MEMBER(volume.tetgen.steiner_on_sheets),
                      "let TetGen add points on the sheets and box (false: each sheet triangle "
                      "stays one face, the box faces are seeded)"));
  rows.push_back(Number("tet.time_limit_seconds", SM_MEMBER(volume.tetgen.time_limit_seconds),
                        "(0, 86400]", "seconds",
                        "the volume stage's time: TetGen is stopped beyond it (an error: no "
                        "mesh), the improvement and the sliver rounds keep what they reached; "
                        "a second try from moved seeds runs only where half of it is left"));
  rows.push_back(Integer("tet.memory_limit_bytes", SM_MEMBER(volume.tetgen.memory_limit_bytes),
                         "[67108864, 1099511627776]", "bytes", "TetGen's memory limit"));
  rows.push_back(Local(Text("tet.program", SM_MEMBER(volume.tetgen.program),
                            "the TetGen program (looked up on PATH)")));
  rows.push_back(Bool(
      "plc.repair", SM_MEMBER(volume.plc.repair),
      "drop the smaller of each pair of sheet triangles untangling left clashing (else fail)"));
  rows.push_back(Number("plc.snap_voxels", SM_MEMBER(volume.plc.snap_voxels), "[0, 10]", "voxels",
                        "sheet vertices this close to the box move onto it"));
  rows.push_back(Number("plc.snap_clear_voxels", SM_MEMBER(volume.plc.snap_clear_voxels), "[0, 10]",
                        "voxels", "so do vertices this close, unless that makes a clash"));
  rows.push_back(Number("plc.flip_fold_degrees", SM_MEMBER(volume.plc.flip_fold_degrees), "[0, 90)",
                        "degrees",
                        "flip sheet edges between triangles this close to coplanar where that "
                        "gives better triangles (0: none)"));
  rows.push_back(Number("plc.cap_degrees", SM_MEMBER(volume.plc.cap_degrees), "(90, 180]",
                        "degrees", "a sheet triangle with an angle over this is flat (a cap)"));
  rows.push_back(Number("plc.overlap_voxels", SM_MEMBER(volume.plc.overlap_voxels), "[0, 10]",
                        "voxels",
                        "drop a rim triangle this close to another sheet, nearly parallel to it "
                        "(0: keep all)"));
  rows.push_back(Number("plc.overlap_degrees", SM_MEMBER(volume.plc.overlap_degrees), "[0, 90)",
                        "degrees", "what nearly parallel means for plc.overlap_voxels"));
  rows.push_back(Number("plc.wedge_degrees", SM_MEMBER(volume.plc.wedge_degrees), "[0, 30]",
                        "degrees",
                        "open wedges narrower than this between a sheet edge and a sheet face "
                        "(0: never)"));
  rows.push_back(Number("plc.wedge_voxels", SM_MEMBER(volume.plc.wedge_voxels), "[0, 5]", "voxels",
                        "the farthest a vertex moves to open a wedge"));
  rows.push_back(Number("plc.junction_voxels", SM_MEMBER(volume.plc.junction_voxels), "[0, 5]",
                        "voxels",
                        "the farthest a junction vertex moves onto the line between its "
                        "neighbours on the junction, where a wedge there is under "
                        "plc.wedge_degrees (0: never)"));
  rows.push_back(Number("plc.short_edge_voxels", SM_MEMBER(volume.plc.short_edge_voxels), "[0, 5]",
                        "voxels",
                        "collapse sheet edges shorter than this where that makes no fold or "
                        "clash (0: none)"));
  rows.push_back(Number("plc.long_edge_factor", SM_MEMBER(volume.plc.long_edge_factor),
                        "0 | [1.5, 20]", "",
                        "sheet edges longer than this many times the sheets' median edge are "
                        "halved in their plane before TetGen (0: none)"));
  rows.push_back(Number("plc.untangle_voxels", SM_MEMBER(volume.plc.untangle_voxels), "[0, 3]",
                        "voxels",
                        "sheet triangles that cut through each other are untangled by moving a "
                        "vertex at most this far, or flipping an edge (0: none)"));
  rows.push_back(Number("plc.contact_voxels", SM_MEMBER(volume.plc.contact_voxels), "[0, 3]",
                        "voxels",
                        "a sheet vertex this near another sheet moves onto it, joining the two "
                        "(0: none)"));
  rows.push_back(Bool("plc.zip_rims", SM_MEMBER(volume.plc.zip_rims),
                      "two sheet edges passing within plc.contact_voxels of each other are joined "
                      "where they pass closest, so a rim along another sheet is zipped onto it"));
  rows.push_back(Number("plc.lattice", SM_MEMBER(volume.plc.lattice), "0 | [0.25, 8]", "",
                        "seed a graded lattice off the sheets, spaced this many median sheet "
                        "edges (0: none)"));
  rows.push_back(Number("plc.grading", SM_MEMBER(volume.plc.grading), "[0.1, 4]", "",
                        "how fast the lattice's spacing grows away from the sheets (it doubles "
                        "every 1 / grading spacings)"));
  rows.push_back(Integer("improve.passes", SM_MEMBER(volume.improve.passes), "[0, 100]", "",
                         "rounds of flips, smoothing and insertion on TetGen's output (0: none)"));
  rows.push_back(Number("improve.target_degrees", SM_MEMBER(volume.improve.target_degrees),
                        "[0, 70.6]", "degrees", "tetrahedra below this are improved"));
  rows.push_back(Number("improve.insert_below_degrees",
                        SM_MEMBER(volume.improve.insert_below_degrees), "[0, 70.6]", "degrees",
                        "tetrahedra still below this after the flips get a new vertex beside them "
                        "(at most improve.target_degrees; 0: none)"));
  rows.push_back(Number("improve.insert_again_below_degrees",
                        SM_MEMBER(volume.improve.insert_again_below_degrees), "[0, 70.6]",
                        "degrees",
                        "after the first pass, only tetrahedra below this get a new vertex (the "
                        "lower of it and improve.insert_below_degrees applies)"));
  rows.push_back(Number("improve.floor_degrees", SM_MEMBER(volume.improve.smoothing_floor_degrees),
                        "[0, 70.6]", "degrees",
                        "smoothing for the mean never lowers a vertex's worst tetrahedron below "
                        "this"));
  rows.push_back(Number("improve.split_sheets_below_degrees",
                        SM_MEMBER(volume.improve.split_sheets_below_degrees), "[0, 70.6]",
                        "degrees",
                        "a tetrahedron below this may get its new vertex on a sheet face or edge "
                        "(0: every sheet triangle stays one face)"));
  rows.push_back(Number("improve.sheet_move_voxels", SM_MEMBER(volume.improve.sheet_move_voxels),
                        "[0, 10]", "voxels",
                        "for a tetrahedron below improve.split_sheets_below_degrees, the sheet "
                        "vertices of its star may move this far (half at a junction, none on "
                        "the box; 0: the PLC's vertices stay)"));
  rows.push_back(Number("improve.radius_weight", SM_MEMBER(volume.improve.radius_weight), "[0, 1]",
                        "",
                        "smoothing raises the mean of (1 - w) min dihedral + w 70.53 degrees "
                        "radius aspect"));
  return rows;
}

std::vector<ParamRow> FlowRows() {
  std::vector<ParamRow> rows;
  rows.push_back(Bool(
      "flow", SM_MEMBER(flow.enabled),
      "the sample's permeability tensor on the volume mesh, which it turns on (Darcy flow in the "
      "rock, the cubic law a³/12 on each sheet face, three unit gradients)"));
  rows.push_back(Number("permeability.matrix", SM_MEMBER(flow.matrix_permeability),
                        "[1e-25, 0.001]", "m²",
                        "permeability of the rock between the sheets (1e-18 m²: about a "
                        "microdarcy, a tight rock)"));
  rows.push_back(Number("permeability.body", SM_MEMBER(flow.body_permeability),
                        "0 | [1e-25, 0.001]", "m²",
                        "permeability inside the pieces meshed as bodies; 0: each body's own, "
                        "the parallel-plate law a²/12 of its thickness a = 2 × volume / wall area "
                        "(a thick fracture meshed as a body carries what it would as a sheet)"));
  rows.push_back(Bool("permeability.image_reference", SM_MEMBER(flow.image_reference),
                      "with flow: also the image's own answer (the cubic law on the sheet "
                      "voxels, finite volumes on the voxel grid, up to a million voxels) and the "
                      "mesh / image ratio per axis; it can take longer than the volume mesh"));
  return rows;
}

std::vector<ParamRow> OutputRows() {
  std::vector<ParamRow> rows;
  rows.push_back(Formats("output.formats",
                         {{"ply", &OutputOptions::ply},
                          {"vtp", &OutputOptions::vtp},
                          {"vtu", &OutputOptions::surface_vtu},
                          {"obj", &OutputOptions::obj}},
                         "surface mesh files to write"));
  rows.push_back(Bool("output.model", SM_MEMBER(output.model),
                      "with extraction: the model (model.vdb, its voxels and labels, sparse; "
                      "pieces.csv)"));
  rows.push_back(Choice(
      "output.label_volume", SM_MEMBER(output.label_volume),
      {{"none", DenseLabels::kNone}, {"hdf5", DenseLabels::kHdf5}, {"raw", DenseLabels::kRaw}},
      "with extraction: also the model's labels as a dense volume the size of "
      "the box — model_labels_<dims>.h5 (dataset labels, chunked and "
      "compressed) or model_labels_<dims>_u16.raw (2 bytes a voxel); none: "
      "model.vdb has them sparse"));
  rows.push_back(Bool("output.dropped", SM_MEMBER(output.dropped),
                      "with extraction: the voxels the model dropped, labelled by why "
                      "(dropped_labels_<dims>.h5, or _u16.raw with output.label_volume raw: 1 "
                      "refine, 2 specks, 3 crossings, 4 minor pieces)"));
  rows.push_back(Bool("output.previews", SM_MEMBER(output.previews),
                      "PNG previews: three slices through the middle with the phase and the "
                      "mesh's cross-section, and the largest sheet's thickness map"));
  rows.push_back(Formats("output.volume_formats",
                         {{"vtu", &OutputOptions::vtu},
                          {"msh", &OutputOptions::msh},
                          {"inp", &OutputOptions::inp},
                          {"exo", &OutputOptions::exo}},
                         "volume mesh files to write"));
  rows.push_back(Bool("output.split", SM_MEMBER(output.split),
                      "also the volume mesh split along the sheets for mechanics, which it turns "
                      "on: each sheet node copied per side (not on a rim inside the rock), "
                      "volume_split.inp (Abaqus, COH3D6 cohesive elements), volume_split_ccx.inp "
                      "(CalculiX, a contact pair per sheet) and volume_split.exo (side sets "
                      "sheet_<p>_neg / _pos), as inp and exo are among the volume formats"));
  rows.push_back(Number("time_limit_seconds", SM_MEMBER(time_limit_seconds), "0 | (0, 2592000]",
                        "seconds",
                        "wall-clock limit of the run (0: none of its own; a server's "
                        "--job_time_limit_seconds caps it)"));
  return rows;
}

#undef SM_MEMBER

}  // namespace sheetmesh::parameter_rows
