#include "worker/pipeline/surface/representation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/status_macros.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/body_surface.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/voxel/components.h"

namespace sheetmesh {
namespace {

// The faces of `mesh` listed in `faces`, with only the vertices they use; `renumbered`, when
// given, maps each vertex of `mesh` to its index there (UINT32_MAX where unused).
TriangleMesh SubMesh(const TriangleMesh& mesh, const std::vector<uint32_t>& faces,
                     std::vector<uint32_t>* renumbered = nullptr) {
  TriangleMesh out;
  std::vector<uint32_t> local;
  std::vector<uint32_t>& index = renumbered != nullptr ? *renumbered : local;
  index.assign(mesh.vertices.size(), UINT32_MAX);
  const bool vthick = mesh.vertex_thickness_voxels.size() == mesh.vertices.size();
  for (const uint32_t f : faces) {
    Face face;
    for (int k = 0; k < 3; ++k) {
      uint32_t& v = index[mesh.faces[f][k]];
      if (v == UINT32_MAX) {
        v = static_cast<uint32_t>(out.vertices.size());
        out.vertices.push_back(mesh.vertices[mesh.faces[f][k]]);
        if (vthick)
          out.vertex_thickness_voxels.push_back(mesh.vertex_thickness_voxels[mesh.faces[f][k]]);
      }
      face[k] = v;
    }
    out.faces.push_back(face);
    out.face_thickness_voxels.push_back(mesh.face_thickness_voxels[f]);
    if (!mesh.face_aperture_voxels.empty())
      out.face_aperture_voxels.push_back(mesh.face_aperture_voxels[f]);
    out.face_piece.push_back(mesh.face_piece[f]);
  }
  return out;
}

// Appends `part` to `mesh` (vertices renumbered; vertex thickness and face aperture 0 where
// one of them has none and the other has).
void Append(const TriangleMesh& part, TriangleMesh* mesh) {
  const uint32_t base = static_cast<uint32_t>(mesh->vertices.size());
  mesh->vertices.insert(mesh->vertices.end(), part.vertices.begin(), part.vertices.end());
  if (part.vertex_thickness_voxels.size() == part.vertices.size()) {
    mesh->vertex_thickness_voxels.insert(mesh->vertex_thickness_voxels.end(),
                                         part.vertex_thickness_voxels.begin(),
                                         part.vertex_thickness_voxels.end());
  } else {
    mesh->vertex_thickness_voxels.resize(mesh->vertices.size(), 0.0f);
  }
  if (!part.face_aperture_voxels.empty() || !mesh->face_aperture_voxels.empty()) {
    mesh->face_aperture_voxels.resize(mesh->faces.size(), 0.0f);
    if (part.face_aperture_voxels.empty()) {
      mesh->face_aperture_voxels.resize(mesh->faces.size() + part.faces.size(), 0.0f);
    } else {
      mesh->face_aperture_voxels.insert(mesh->face_aperture_voxels.end(),
                                        part.face_aperture_voxels.begin(),
                                        part.face_aperture_voxels.end());
    }
  }
  for (const Face& f : part.faces) mesh->faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  mesh->face_thickness_voxels.insert(mesh->face_thickness_voxels.end(),
                                     part.face_thickness_voxels.begin(),
                                     part.face_thickness_voxels.end());
  mesh->face_piece.insert(mesh->face_piece.end(), part.face_piece.begin(), part.face_piece.end());
}

// Merges vertices at exactly the same place (pieces split apart by SubMesh share their
// junctions' vertices again).
void WeldExact(TriangleMesh* mesh) {
  std::map<std::array<double, 3>, uint32_t> first;
  std::vector<uint32_t> to(mesh->vertices.size());
  TriangleMesh out;
  const bool vthick = mesh->vertex_thickness_voxels.size() == mesh->vertices.size();
  for (uint32_t v = 0; v < mesh->vertices.size(); ++v) {
    const Vec3& p = mesh->vertices[v];
    auto [it, fresh] = first.try_emplace({p.x, p.y, p.z}, out.vertices.size());
    if (fresh) {
      out.vertices.push_back(p);
      if (vthick) out.vertex_thickness_voxels.push_back(mesh->vertex_thickness_voxels[v]);
    }
    to[v] = it->second;
  }
  for (Face& f : mesh->faces)
    for (uint32_t& v : f) v = to[v];
  mesh->vertices = std::move(out.vertices);
  if (vthick) mesh->vertex_thickness_voxels = std::move(out.vertex_thickness_voxels);
}

// Each piece's voxels (linear indices, ascending) and their τ.
struct PieceVoxels {
  std::vector<uint64_t> keys;
  std::vector<uint16_t> tau;
};

// The bounding box of `mesh`'s vertices.
void Bounds(const TriangleMesh& mesh, Vec3* lo, Vec3* hi) {
  *lo = Vec3(1e300, 1e300, 1e300);
  *hi = Vec3(-1e300, -1e300, -1e300);
  for (const Vec3& p : mesh.vertices) {
    for (int k = 0; k < 3; ++k) {
      (*lo)[k] = std::min((*lo)[k], p[k]);
      (*hi)[k] = std::max((*hi)[k], p[k]);
    }
  }
}

// A sheet around a body (a lens made one, or any sheet crossing a body): its faces with a
// corner inside the body go (but those of `skip_piece`, joined to it before), and the rim
// they leave moves onto the body's surface (the nearest point, where that is within
// two of the sheet's mean edge lengths), so that the two meet without a gap or an
// overlap: the volume mesh joins them where a sheet vertex lies on a body face.
TriangleMesh JoinToBody(const TriangleMesh& sheet, const TriangleMesh& body,
                        int32_t skip_piece = -1) {
  Vec3 lo, hi;
  Bounds(body, &lo, &hi);
  auto in_box = [&](const Vec3& p) {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  };
  std::vector<uint8_t> inside(sheet.vertices.size(), 0);
  for (const Face& f : sheet.faces) {
    for (uint32_t v : f) {
      if (inside[v] != 0) continue;
      const Vec3& p = sheet.vertices[v];
      inside[v] = in_box(p) && InsideClosedSurface(p, body.vertices, body.faces) ? 2 : 1;
    }
  }
  std::vector<uint32_t> kept;
  std::vector<uint8_t> rim(sheet.vertices.size(), 0);
  for (uint32_t f = 0; f < sheet.faces.size(); ++f) {
    const Face& t = sheet.faces[f];
    if (sheet.face_piece[f] != skip_piece &&
        (inside[t[0]] == 2 || inside[t[1]] == 2 || inside[t[2]] == 2)) {
      for (uint32_t v : t) rim[v] = 1;
    } else {
      kept.push_back(f);
    }
  }
  const double reach = 2 * MeanEdgeLength(sheet);
  std::vector<uint32_t> index;
  TriangleMesh out = SubMesh(sheet, kept, &index);
  for (uint32_t v = 0; v < sheet.vertices.size(); ++v) {
    if (!rim[v] || index[v] == UINT32_MAX) continue;
    Vec3 best = out.vertices[index[v]];
    double nearest = reach * reach;
    for (size_t f = 0; f < body.faces.size(); ++f) {
      const Vec3 c = ClosestPointOnTriangle(sheet.vertices[v], Corners(body, f));
      const double d = Norm2(c - sheet.vertices[v]);
      if (d < nearest) nearest = d, best = c;
    }
    out.vertices[index[v]] = best;
  }
  return out;
}

// Whether a face of `sheet` cuts through a face of `body` (beyond touching it: each sheet
// face is shrunk by a hair first, so a rim vertex joined onto the body does not count, and
// a face with two corners joined onto it is a rim's chord, left to the volume mesh).
// A join that leaves such a cut (a sheet face spanning a bump of the body, rims of two
// sheets projected across each other) is refused: the volume mesh could only mend it by
// removing triangles, and a body missing a wall triangle leaks into the rock.
bool CutsThrough(const TriangleMesh& sheet, const TriangleMesh& body) {
  constexpr double kHair = 1e-3;
  Vec3 lo, hi;
  Bounds(body, &lo, &hi);
  for (size_t f = 0; f < sheet.faces.size(); ++f) {
    const Triangle t = Corners(sheet, f);
    Vec3 tlo, thi;
    TriangleBox(t, 0, &tlo, &thi);
    if (tlo.x > hi.x || tlo.y > hi.y || tlo.z > hi.z || thi.x < lo.x || thi.y < lo.y ||
        thi.z < lo.z) {
      continue;
    }
    // A rim face with two corners joined onto the body spans a chord of it, dipping inside
    // by the sagitta where the body curves: the volume mesh's untangling splits it there.
    int on_body = 0;
    for (const Vec3& p : t) {
      for (size_t g = 0; g < body.faces.size(); ++g) {
        if (PointTriangleDistance2(p, Corners(body, g)) < 1e-12) {
          ++on_body;
          break;
        }
      }
    }
    if (on_body >= 2) continue;
    const Triangle small = Shrink(t, kHair);
    for (size_t g = 0; g < body.faces.size(); ++g) {
      if (TrianglesIntersect(small, Corners(body, g), 0)) return true;
    }
  }
  return false;
}

// Whether a face of a piece other than `piece` comes near `part`: a corner within `margin`
// voxels of its bounding box. A sheet running through or ending on a body would have to be
// joined to its walls, and where several are (a crossing of fractures cut into pieces, a
// network's pieces meeting at a vug) the joins clash and the volume mesh must remove wall
// triangles (a body then leaks into the rock); such a part stays a sheet.
// Within this many voxels of a body, another piece's sheet would be joined to it (the volume
// mesh mends contacts within 1.5).
constexpr double kNearVoxels = 2.0;

bool NearOthers(const TriangleMesh& mesh, int32_t piece, const VoxelSet& part, double margin) {
  Index3 lo, hi;
  part.Bounds(&lo, &hi);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_piece[f] == piece) continue;
    for (uint32_t v : mesh.faces[f]) {
      const Vec3& p = mesh.vertices[v];
      if (p.x >= lo.x - margin && p.x <= hi.x + margin && p.y >= lo.y - margin &&
          p.y <= hi.y + margin && p.z >= lo.z - margin && p.z <= hi.z + margin) {
        return true;
      }
    }
  }
  return false;
}

double Median(std::vector<uint16_t> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// A thick part of a piece is at least this many voxels, and has at least this many sheet
// faces over it: a closed surface needs four, a lens of fewer voxels is noise.
constexpr uint64_t kMinLensVoxels = 64;
constexpr size_t kMinLensFaces = 8;

// Scores `sheet_faces` (the sheet over `own`) and the body of `own` with as many faces into
// `choice`; returns the body.
absl::StatusOr<BodySurface> Trial(const TriangleMesh& sheet_faces, const VoxelSet& own,
                                  int32_t piece, PrismHeight height, PieceRepresentation* choice) {
  const Dims& dims = own.dims();
  SM_ASSIGN_OR_RETURN(VoxelSet prisms, VoxelizePrisms(sheet_faces, dims, height));
  choice->sheet_similarity = ScoreModel(prisms, own).similarity;
  SM_ASSIGN_OR_RETURN(BodySurface body, MeshBody(own, piece, sheet_faces.num_faces()));
  SM_ASSIGN_OR_RETURN(VoxelSet inside, VoxelizeClosedSurface(body.mesh, dims));
  choice->body_similarity = ScoreModel(inside, own).similarity;
  choice->body_triangles = body.mesh.faces.size();
  choice->body_triangles_before = body.faces_before;
  return body;
}

// A body is at least this many of its mean edge lengths thick (its median τ): thinner,
// the volume mesh fills it with tetrahedra as flat as it is thin against its triangles
// (a 2-voxel sheet with a lens meshed whole as a body kept 1.7°).
constexpr double kBodyThicknessPerEdge = 0.5;

// Where the surface is the result, thin pieces are tried as bodies up to this many voxels
// in all (in the order of their ids): their closed surfaces at voxel resolution cost about
// 10-30 µs a voxel to build, decimate and score (a 3.07 M-voxel sheet of a grey scan: 89 s
// for its trial, 16 s for the rest of the run), so a volume at scale keeps its sheets
// rather than spend minutes on trials. Stout pieces are always tried.
constexpr uint64_t kThinBodyTrialVoxels = uint64_t{1} << 19;

// The longest side of the bounding box of voxels given by linear index.
double Width(std::span<const uint64_t> keys, const Dims& d) {
  int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  for (const uint64_t k : keys) {
    const int64_t c[3] = {static_cast<int64_t>(k % d.nx), static_cast<int64_t>(k / d.nx % d.ny),
                          static_cast<int64_t>(k / d.nx / d.ny)};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a]);
    }
  }
  return keys.empty() ? 0.0 : double(std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) + 1);
}

// Whether a part with median thickness `median` and `width` (the longest side of its
// bounding box) is as thick as it is wide, within `aspect`. A crossing of two thin sheets
// is thick along a line as long as the sheets are wide: not stout.
bool Stout(double median, double width, double aspect) {
  return median > 0 && median >= aspect * width;
}

// Whether a body of `voxels` voxels with median thickness `median` could be thick enough
// for `faces` triangles, judged before building it: its two walls' area, 2 voxels / median,
// in equilateral triangles of that count (a body whose triangles would be wider than
// twice its thickness is not worth building).
bool MayBeThickEnough(uint64_t voxels, double median, uint64_t faces) {
  if (median <= 0 || faces == 0) return false;
  const double area = 2.0 * voxels / median;
  const double edge = std::sqrt(4 * area / (std::sqrt(3.0) * faces));
  return median >= kBodyThicknessPerEdge * edge;
}

// Whether a body scored in `choice` beats its sheet, keeps to the sheet's share of the
// triangles (its decimation may stop short of it where the outline needs more) and, unless
// thin bodies are allowed, is thick enough for its triangles.
bool BodyWins(const PieceRepresentation& choice, const TriangleMesh& body, bool thin) {
  return choice.body_triangles <= (1 + kTriangleTolerance) * choice.sheet_triangles &&
         (thin || choice.median_thickness >= kBodyThicknessPerEdge * MeanEdgeLength(body)) &&
         *choice.body_similarity > *choice.sheet_similarity;
}

// Why BodyWins chose as it did, in words.
std::string TrialReason(const PieceRepresentation& choice, const TriangleMesh& body, bool thin) {
  const double sheet = *choice.sheet_similarity, closed = *choice.body_similarity;
  if (choice.body_triangles > (1 + kTriangleTolerance) * choice.sheet_triangles) {
    return absl::StrFormat("its body needs %d triangles, over the sheet's %d",
                           choice.body_triangles, choice.sheet_triangles);
  }
  if (!thin && choice.median_thickness < kBodyThicknessPerEdge * MeanEdgeLength(body)) {
    return absl::StrFormat(
        "its body's triangles (mean edge %.1f voxels) are too wide for its median thickness %.1f",
        MeanEdgeLength(body), choice.median_thickness);
  }
  return absl::StrFormat("as a body it scores %.4f, as a sheet %.4f", closed, sheet);
}

// The thick parts of a piece: 6-connected sets of its voxels whose τ is at least `least`,
// of kMinLensVoxels or more, each as its sorted voxel keys.
absl::StatusOr<std::vector<std::vector<uint64_t>>> ThickParts(const PieceVoxels& pv,
                                                              const Dims& dims, double least) {
  std::vector<uint64_t> thick;
  for (size_t i = 0; i < pv.keys.size(); ++i) {
    if (pv.tau[i] >= least) thick.push_back(pv.keys[i]);
  }
  std::vector<std::vector<uint64_t>> parts;
  if (thick.size() < kMinLensVoxels) return parts;
  const VoxelSet set = VoxelSetFromSortedLinear(dims, thick);
  SM_ASSIGN_OR_RETURN(Components c, LabelComponents(set, Connectivity::k6));
  const std::vector<uint32_t> label = c.VoxelLabels(set);
  std::vector<std::vector<uint64_t>> keys(c.count());
  set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    if (c.sizes[label[i]] < kMinLensVoxels) return;
    keys[label[i]].push_back(static_cast<uint64_t>(x) +
                             dims.nx * (y + static_cast<uint64_t>(dims.ny) * z));
  });
  for (std::vector<uint64_t>& k : keys) {
    if (!k.empty()) parts.push_back(std::move(k));
  }
  return parts;
}

// The faces of `mesh` whose centroid lies in a voxel of `part`, and the others.
void SplitFaces(const TriangleMesh& mesh, const VoxelSet& part, std::vector<uint32_t>* in,
                std::vector<uint32_t>* out) {
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const auto t = Corners(mesh, f);
    const Vec3 c = (t[0] + t[1] + t[2]) / 3.0;
    const bool inside = part.Contains(std::llround(c.x), std::llround(c.y), std::llround(c.z));
    (inside ? in : out)->push_back(f);
  }
}

// What the choice has made so far: the bodies (one mesh, and each on its own for the
// joins), the next free piece id and the report.
struct Chosen {
  struct Joined {
    TriangleMesh mesh;
    int32_t piece = -1;  // the piece whose sheet was joined to it already (a lens's)
  };
  TriangleMesh bodies;
  std::vector<Joined> joined;
  int32_t next_id = 0;  // for lenses cut out of pieces: after every id in use
  RepresentationReport report;

  void Add(const TriangleMesh& body, int32_t piece, int32_t joined_to) {
    joined.push_back({body, joined_to});
    Append(body, &bodies);
    bodies.body_pieces.push_back(piece);
  }
};

// Where `piece` (its voxels `pv`, median thickness `median`, its sheet `*sheet_part`) opens
// into lenses, tries each as a body in place of the sheet faces over it, both scored over
// the whole piece; a lens that wins joins the bodies and the sheet keeps the rest, joined
// to it.
absl::Status TryLenses(const SheetAnalysis& sheet, const TriangleMesh& mesh, const PieceVoxels& pv,
                       int32_t piece, double median, const RepresentationOptions& options,
                       TriangleMesh* sheet_part, Chosen* chosen) {
  const Dims& dims = sheet.set.dims();
  // Voxels at least twice as thick as the piece's median (and body_min_thickness).
  const double least = std::max(options.body_min_thickness, 2 * median);
  SM_ASSIGN_OR_RETURN(const std::vector<std::vector<uint64_t>> parts, ThickParts(pv, dims, least));
  std::optional<VoxelSet> own;
  double score = 0;  // the piece's, as it stands
  for (const std::vector<uint64_t>& keys : parts) {
    // One part's set at a time: a set holds an index of the box's rows (33 MB at 2048³).
    const VoxelSet part = VoxelSetFromSortedLinear(dims, keys);
    std::vector<uint32_t> over, rest;
    SplitFaces(*sheet_part, part, &over, &rest);
    if (over.size() < kMinLensFaces || NearOthers(mesh, piece, part, kNearVoxels)) continue;
    PieceRepresentation lens;
    lens.piece = chosen->next_id;
    lens.part_of = piece;
    lens.voxels = part.size();
    lens.sheet_triangles = over.size();
    std::vector<uint16_t> tau;
    double sum = 0;
    part.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
      tau.push_back(sheet.thickness[sheet.set.Find(x, y, z)]);
      sum += tau.back();
    });
    lens.thickness = sum / part.size();
    lens.median_thickness = Median(std::move(tau));
    Index3 lo, hi;
    part.Bounds(&lo, &hi);
    const double width = double(std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) + 1);
    if (!Stout(lens.median_thickness, width, options.body_min_aspect) ||
        !MayBeThickEnough(part.size(), lens.median_thickness, over.size())) {
      continue;
    }
    if (!own) {
      own = VoxelSetFromSortedLinear(dims, pv.keys);
      SM_ASSIGN_OR_RETURN(VoxelSet prisms, VoxelizePrisms(*sheet_part, dims, options.height));
      score = ScoreModel(prisms, *own).similarity;
    }
    SM_ASSIGN_OR_RETURN(BodySurface body, MeshBody(part, lens.piece, over.size()));
    lens.body_triangles = body.mesh.num_faces();
    lens.body_triangles_before = body.faces_before;
    TriangleMesh kept = JoinToBody(*sheet_part, body.mesh);
    SM_ASSIGN_OR_RETURN(VoxelSet with_body, VoxelizePrisms(kept, dims, options.height));
    SM_ASSIGN_OR_RETURN(VoxelSet inside, VoxelizeClosedSurface(body.mesh, dims));
    lens.sheet_similarity = score;
    lens.body_similarity = ScoreModel(Union(with_body, inside), *own).similarity;
    if (!BodyWins(lens, body.mesh, false) || CutsThrough(kept, body.mesh)) continue;
    lens.body = true;
    lens.reason =
        absl::StrCat("a thick part of piece ", piece, ": ", TrialReason(lens, body.mesh, false));
    score = *lens.body_similarity;
    *sheet_part = std::move(kept);
    chosen->Add(body.mesh, chosen->next_id++, piece);
    chosen->report.pieces.push_back(lens);
    ++chosen->report.bodies;
  }
  return absl::OkStatus();
}

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

absl::StatusOr<RepresentationReport> ChooseRepresentation(const SheetAnalysis& sheet,
                                                          std::span<const int32_t> piece_of_voxel,
                                                          const RepresentationOptions& options,
                                                          TriangleMesh* mesh,
                                                          const Progress& progress) {
  if (mesh->face_piece.size() != mesh->faces.size() ||
      mesh->face_thickness_voxels.size() != mesh->faces.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("choosing representations needs a piece and a thickness per face: ",
                     mesh->face_piece.size(), " and ", mesh->face_thickness_voxels.size(), " for ",
                     mesh->faces.size(), " faces"));
  }
  Chosen chosen;
  chosen.report.mode = options.mode;
  std::map<int32_t, std::vector<uint32_t>> faces_of;
  for (uint32_t f = 0; f < mesh->faces.size(); ++f) faces_of[mesh->face_piece[f]].push_back(f);
  if (options.mode == RepresentationMode::kSheet || faces_of.empty()) return chosen.report;

  const Dims& dims = sheet.set.dims();
  std::map<int32_t, PieceVoxels> voxels_of;
  chosen.next_id = faces_of.rbegin()->first + 1;
  {
    std::vector<uint32_t> component;
    if (piece_of_voxel.empty()) component = sheet.components.VoxelLabels(sheet.set);
    const auto piece_of = [&](uint64_t i) {
      return piece_of_voxel.empty() ? static_cast<int32_t>(component[i]) : piece_of_voxel[i];
    };
    // Counted first, so that every piece's lists are allocated once at their size (grown
    // by doubling they held up to twice the model's voxels: 3 GB at 2048³).
    std::map<int32_t, uint64_t> count;
    for (uint64_t i = 0; i < sheet.set.size(); ++i) {
      const int32_t p = piece_of(i);
      chosen.next_id = std::max(chosen.next_id, p + 1);
      if (faces_of.count(p)) ++count[p];
    }
    for (const auto& [p, n] : count) {
      voxels_of[p].keys.reserve(n);
      voxels_of[p].tau.reserve(n);
    }
    sheet.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
      auto it = voxels_of.find(piece_of(i));
      if (it == voxels_of.end()) return;
      PieceVoxels& v = it->second;
      v.keys.push_back(static_cast<uint64_t>(x) +
                       dims.nx * (y + static_cast<uint64_t>(dims.ny) * z));
      v.tau.push_back(sheet.thickness[i]);
    });
  }

  const bool body_mode = options.mode == RepresentationMode::kBody;
  uint64_t thin_tried = 0;  // voxels of thin pieces tried as bodies
  TriangleMesh sheets;
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
      double sum = 0;
      for (uint16_t t : pv.tau) sum += t;
      choice.thickness = sum / pv.keys.size();
      choice.median_thickness = Median(pv.tau);
      const bool thin = options.try_thin_bodies;
      const bool thin_trial = thin && thin_tried + choice.voxels <= kThinBodyTrialVoxels;
      if (thin_trial) thin_tried += choice.voxels;
      const double width = Width(pv.keys, dims);
      if (choice.median_thickness < options.body_min_thickness) {
        choice.reason = absl::StrFormat(
            "thin: median thickness %.1f voxels, under surface.body_min_thickness %g",
            choice.median_thickness, options.body_min_thickness);
      } else if (!Stout(choice.median_thickness, width, options.body_min_aspect)) {
        choice.reason = absl::StrFormat(
            "thin against its width: median thickness %.1f voxels, %.2f of its width %.0f, "
            "under surface.body_min_aspect %g",
            choice.median_thickness, choice.median_thickness / width, width,
            options.body_min_aspect);
      } else if (!MayBeThickEnough(choice.voxels, choice.median_thickness, faces.size())) {
        choice.reason =
            absl::StrFormat("its %d triangles would be wider than twice its median thickness %.1f",
                            faces.size(), choice.median_thickness);
      }
      if (body_mode || thin_trial || choice.reason.empty()) {
        const VoxelSet own = VoxelSetFromSortedLinear(dims, pv.keys);
        SM_ASSIGN_OR_RETURN(BodySurface body,
                            Trial(sheet_part, own, piece, options.height, &choice));
        // Another piece's sheet near a body would be joined to it in a volume mesh; where
        // the surface is the result, the two may simply lie side by side.
        const bool wins = BodyWins(choice, body.mesh, thin);
        const bool near = wins && !thin && NearOthers(*mesh, piece, own, kNearVoxels);
        choice.body = body_mode || (wins && !near);
        choice.reason =
            body_mode ? "surface.representation = body"
            : near    ? absl::StrFormat("another piece's sheet runs within %g voxels of its body",
                                        kNearVoxels)
                      : TrialReason(choice, body.mesh, thin);
        if (choice.body) {
          chosen.Add(body.mesh, piece, -1);
          sheet_part = TriangleMesh();
        }
      }
      if (!choice.body && !body_mode) {
        SM_RETURN_IF_ERROR(TryLenses(sheet, *mesh, pv, piece, choice.median_thickness, options,
                                     &sheet_part, &chosen));
        choice.sheet_triangles = sheet_part.num_faces();
      }
    }
    if (choice.reason.empty()) choice.reason = "no voxels of its own to try as a body";
    if (choice.body) ++chosen.report.bodies;
    Append(sheet_part, &sheets);
    chosen.report.pieces.push_back(choice);
    SM_RETURN_IF_ERROR(progress.Update(static_cast<double>(++done) / faces_of.size()));
  }
  // Sheets that cross a body end on its walls (a fracture running into a vug), as a lens's
  // own sheet does.
  for (const Chosen::Joined& b : chosen.joined) {
    if (!sheets.faces.empty()) sheets = JoinToBody(sheets, b.mesh, b.piece);
  }
  WeldExact(&sheets);
  TriangleMesh out = std::move(sheets);
  Append(chosen.bodies, &out);
  out.body_pieces = chosen.bodies.body_pieces;
  std::sort(out.body_pieces.begin(), out.body_pieces.end());
  std::sort(
      chosen.report.pieces.begin(), chosen.report.pieces.end(),
      [](const PieceRepresentation& a, const PieceRepresentation& b) { return a.piece < b.piece; });
  if (chosen.report.bodies > 0) *mesh = std::move(out);
  const std::map<int32_t, double> apertures = EquivalentApertures(*mesh, sheet.set.dims());
  for (PieceRepresentation& p : chosen.report.pieces) {
    const auto it = apertures.find(p.piece);
    if (p.body && it != apertures.end()) p.equivalent_aperture = it->second;
  }
  return chosen.report;
}

}  // namespace sheetmesh
