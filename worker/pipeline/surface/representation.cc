#include "worker/pipeline/surface/representation.h"

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/body_surface.h"
#include "worker/pipeline/surface/surface_builder.h"

namespace sheetmesh {
namespace {

// The faces of `mesh` listed in `faces`, with only the vertices they use.
TriangleMesh SubMesh(const TriangleMesh& mesh, const std::vector<uint32_t>& faces) {
  TriangleMesh out;
  std::vector<uint32_t> index(mesh.vertices.size(), UINT32_MAX);
  const bool vthick = mesh.vertex_thickness.size() == mesh.vertices.size();
  for (const uint32_t f : faces) {
    Face face;
    for (int k = 0; k < 3; ++k) {
      uint32_t& v = index[mesh.faces[f][k]];
      if (v == UINT32_MAX) {
        v = static_cast<uint32_t>(out.vertices.size());
        out.vertices.push_back(mesh.vertices[mesh.faces[f][k]]);
        if (vthick) out.vertex_thickness.push_back(mesh.vertex_thickness[mesh.faces[f][k]]);
      }
      face[k] = v;
    }
    out.faces.push_back(face);
    out.face_thickness.push_back(mesh.face_thickness[f]);
    out.face_piece.push_back(mesh.face_piece[f]);
  }
  return out;
}

// Appends `part` to `mesh` (vertices renumbered; vertex thickness 0 where `part` has none).
void Append(const TriangleMesh& part, TriangleMesh* mesh) {
  const uint32_t base = static_cast<uint32_t>(mesh->vertices.size());
  mesh->vertices.insert(mesh->vertices.end(), part.vertices.begin(), part.vertices.end());
  if (part.vertex_thickness.size() == part.vertices.size()) {
    mesh->vertex_thickness.insert(mesh->vertex_thickness.end(), part.vertex_thickness.begin(),
                                  part.vertex_thickness.end());
  } else {
    mesh->vertex_thickness.resize(mesh->vertices.size(), 0.0f);
  }
  for (const Face& f : part.faces) mesh->faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  mesh->face_thickness.insert(mesh->face_thickness.end(), part.face_thickness.begin(),
                              part.face_thickness.end());
  mesh->face_piece.insert(mesh->face_piece.end(), part.face_piece.begin(), part.face_piece.end());
}

// Each piece's voxels (linear indices, ascending) and the sum of their τ.
struct PieceVoxels {
  std::vector<uint64_t> keys;
  double thickness_sum = 0;
};

}  // namespace

const char* RepresentationName(RepresentationMode mode) {
  switch (mode) {
    case RepresentationMode::kSheet:
      return "sheet";
    case RepresentationMode::kBody:
      return "body";
    case RepresentationMode::kAuto:
      break;
  }
  return "auto";
}

nlohmann::json PieceRepresentation::Fields() const {
  nlohmann::json j = {{"piece", piece},
                      {"representation", body ? "body" : "sheet"},
                      {"voxels", voxels},
                      {"thickness_voxels", thickness},
                      {"sheet_triangles", sheet_triangles}};
  if (sheet_similarity) j["sheet_similarity"] = *sheet_similarity;
  if (body_similarity) {
    j["body_similarity"] = *body_similarity;
    j["body_triangles"] = body_triangles;
    j["body_triangles_before_decimation"] = body_triangles_before;
  }
  return j;
}

nlohmann::json RepresentationReport::Fields() const {
  nlohmann::json j = {{"mode", RepresentationName(mode)}, {"bodies", bodies}};
  j["pieces"] = nlohmann::json::array();
  for (const PieceRepresentation& p : pieces) j["pieces"].push_back(p.Fields());
  return j;
}

absl::StatusOr<RepresentationReport> ChooseRepresentation(const SheetAnalysis& sheet,
                                                          std::span<const int32_t> piece_of_voxel,
                                                          const RepresentationOptions& options,
                                                          TriangleMesh* mesh,
                                                          const Progress& progress) {
  if (mesh->face_piece.size() != mesh->faces.size() ||
      mesh->face_thickness.size() != mesh->faces.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("choosing representations needs a piece and a thickness per face: ",
                     mesh->face_piece.size(), " and ", mesh->face_thickness.size(), " for ",
                     mesh->faces.size(), " faces"));
  }
  RepresentationReport report;
  report.mode = options.mode;
  std::map<int32_t, std::vector<uint32_t>> faces_of;
  for (uint32_t f = 0; f < mesh->faces.size(); ++f) faces_of[mesh->face_piece[f]].push_back(f);
  if (options.mode == RepresentationMode::kSheet || faces_of.empty()) return report;

  const Dims& dims = sheet.set.dims();
  std::map<int32_t, PieceVoxels> voxels_of;
  {
    std::vector<uint32_t> component;
    if (piece_of_voxel.empty()) component = sheet.components.VoxelLabels(sheet.set);
    sheet.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
      const int32_t p =
          piece_of_voxel.empty() ? static_cast<int32_t>(component[i]) : piece_of_voxel[i];
      auto it = faces_of.find(p);
      if (it == faces_of.end()) return;
      PieceVoxels& v = voxels_of[p];
      v.keys.push_back(static_cast<uint64_t>(x) +
                       dims.nx * (y + static_cast<uint64_t>(dims.ny) * z));
      v.thickness_sum += sheet.thickness[i];
    });
  }

  TriangleMesh out;
  size_t done = 0;
  for (const auto& [piece, faces] : faces_of) {
    PieceRepresentation choice;
    choice.piece = piece;
    choice.sheet_triangles = faces.size();
    TriangleMesh sheet_part = SubMesh(*mesh, faces);
    auto vit = voxels_of.find(piece);
    if (vit != voxels_of.end()) {
      const PieceVoxels& pv = vit->second;
      choice.voxels = pv.keys.size();
      choice.thickness = pv.thickness_sum / pv.keys.size();
      const bool try_body = options.mode == RepresentationMode::kBody ||
                            choice.thickness >= options.body_min_thickness;
      if (try_body) {
        const VoxelSet own = VoxelSetFromSortedLinear(dims, pv.keys);
        SM_ASSIGN_OR_RETURN(VoxelSet prisms, VoxelizePrisms(sheet_part, dims, options.height));
        choice.sheet_similarity = ScoreModel(prisms, own).similarity;
        SM_ASSIGN_OR_RETURN(BodySurface body, MeshBody(own, piece, faces.size()));
        SM_ASSIGN_OR_RETURN(VoxelSet inside, VoxelizeClosedSurface(body.mesh, dims));
        choice.body_similarity = ScoreModel(inside, own).similarity;
        choice.body_triangles = body.mesh.faces.size();
        choice.body_triangles_before = body.faces_before;
        // In auto, a body must also keep to the piece's share of the triangles (its
        // decimation may stop short of it where the piece's outline needs more).
        const bool fits = choice.body_triangles <= (1 + kTriangleTolerance) * faces.size();
        choice.body = options.mode == RepresentationMode::kBody ||
                      (fits && *choice.body_similarity > *choice.sheet_similarity);
        if (choice.body) sheet_part = std::move(body.mesh);
      }
    }
    if (choice.body) {
      out.body_pieces.push_back(piece);
      ++report.bodies;
    }
    Append(sheet_part, &out);
    report.pieces.push_back(choice);
    SM_RETURN_IF_ERROR(progress.Update(static_cast<double>(++done) / faces_of.size()));
  }
  if (report.bodies > 0) *mesh = std::move(out);  // body_pieces ascending: the map's order
  return report;
}

}  // namespace sheetmesh
