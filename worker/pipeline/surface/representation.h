// Each piece in the representation that costs least (beyond the paper): a one-layer sheet
// with thickness is right where a piece is thin against its extent; a piece as thick as it
// is wide (a vug, a dissolution slab) or with walls one mid-surface cannot follow is better
// as a body, the closed surface around its voxels (body_surface.h). Each piece is scored
// both ways with its share of the triangles (the sheet faces it has) and keeps the better.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_REPRESENTATION_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_REPRESENTATION_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {

enum class RepresentationMode {
  kAuto,   // each piece as whichever scores better (bodies only from body_min_thickness)
  kSheet,  // every piece a sheet (the paper)
  kBody,   // every piece a body
};

struct RepresentationOptions {
  RepresentationMode mode = RepresentationMode::kAuto;
  // In auto, a piece whose median thickness τ is under this many voxels stays a sheet
  // without a trial: a body that thin makes the volume mesh fill it with tetrahedra no
  // thicker than it, over its whole extent, where a sheet needs none. (Nor does a body win
  // where its median τ is under half its mean edge length.)
  double body_min_thickness = 4.0;
  // In auto, a piece (or a lens of one) is tried as a body only where its median thickness
  // is at least this fraction of its width (the longest side of its bounding box): a
  // fracture 8 voxels thick and 100 wide is a sheet however finely it is meshed, and as a
  // body it would fill the volume mesh with tetrahedra as thin as it (DPM's fractures as
  // bodies at r = 3: the volume mesh ran for minutes); where two sheets cross, the thick
  // part runs along the crossing as far as they are wide. The thick slabs are 0.37-0.44,
  // a vug about 0.5.
  double body_min_aspect = 0.25;
  PrismHeight height = PrismHeight::kFace;  // how a sheet's faces are scored
  // In auto, whether a thin piece is tried as a body too. By default bodies are held to
  // thick pieces (body_min_thickness, body_min_aspect, thick enough for their triangles):
  // a fracture user comes for the aperture, which a body does not carry. Where the surface
  // is the result (no volume mesh, no grey apertures wanted of its sheets) and the user asks
  // (surface.thin_bodies), every piece is tried both ways (thin ones up to about half a
  // million voxels in all: beyond, the trials would cost more than the run) and keeps the
  // better — a planar fracture's closed surface may follow its voxels better than its
  // sheet, at a coarse budget as at a fine one.
  bool try_thin_bodies = false;
};

// One piece's choice, for the report.
struct PieceRepresentation {
  int32_t piece = 0;
  int32_t part_of = -1;  // a thick part (a lens) cut out of this piece as a body of its own
  uint64_t voxels = 0;
  double thickness = 0;                    // mean τ of its voxels
  double median_thickness = 0;             // median τ: a body must be as thick as half its
                                           // triangles are wide
  uint64_t sheet_triangles = 0;            // its share of the budget
  std::optional<double> sheet_similarity;  // formula 5 of its sheet against its voxels
  std::optional<double> body_similarity;   // of its body, when one was tried
  uint64_t body_triangles = 0;             // the body's faces, when tried
  uint64_t body_triangles_before = 0;      // at voxel resolution, before decimation
  bool body = false;                       // chosen as a body
  // A body's equivalent aperture, 2 V / A of its closed surface (volume V, wall area A), in
  // voxels: the thickness of a sheet with its voxels' volume over half its walls' area, the
  // aperture the flow gives it (permeability.body 0: a²/12); 0 for a sheet.
  double equivalent_aperture = 0;
  std::string reason;  // why, in words (the report and the CLI say it)

  nlohmann::json Fields() const;
};

struct RepresentationReport {
  RepresentationMode mode = RepresentationMode::kAuto;
  std::vector<PieceRepresentation> pieces;  // those with sheet faces, by piece id
  uint32_t bodies = 0;

  nlohmann::json Fields() const;
};

const char* RepresentationName(RepresentationMode mode);

// Chooses each piece's representation and replaces the faces of those that become bodies
// in `mesh` by their body's (mesh->body_pieces lists them). Where a piece stays a sheet
// but opens into lenses (6-connected parts at least twice its median thickness and
// body_min_thickness, of 64 voxels or more), each lens is tried in place of the sheet
// faces over it (their centroids in its voxels), both scored over the whole piece, and,
// where it wins, becomes a body with a new piece id (after every id in use; part_of names
// the piece) while the sheet keeps the rest of its faces: the two meet where the sheet's
// faces run into the body. In auto, a piece or lens that another piece's sheet comes near
// (a corner within 2 voxels of its bounding box) stays a sheet, and so does a
// lens whose sheet would cut through it after the join. `piece_of_voxel`, when not
// empty, labels each voxel of sheet.set with its piece (as given to BuildSurface); else
// pieces are the components. Pieces with no sheet face (too small for the SCVD at this r)
// stay without. kInvalidArgument when the mesh carries no face_piece or face_thickness_voxels;
// kCancelled if asked.
absl::StatusOr<RepresentationReport> ChooseRepresentation(const SheetAnalysis& sheet,
                                                          std::span<const int32_t> piece_of_voxel,
                                                          const RepresentationOptions& options,
                                                          TriangleMesh* mesh,
                                                          const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_REPRESENTATION_H_
