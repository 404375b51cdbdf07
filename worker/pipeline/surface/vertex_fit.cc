#include "worker/pipeline/surface/vertex_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <span>
#include <utility>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/mesh/vertex_normals.h"
#include "worker/pipeline/surface/prism_columns.h"

namespace sheetmesh {
namespace {

// The voxels of the columns of `faces` (heights mesh.face_thickness_voxels) that no other prism
// holds, each once: +1 for a voxel of the set, −1 for any other — what these faces add to
// formula 5's numerator on top of the others.
int64_t OwnGain(const TriangleMesh& mesh, std::span<const uint32_t> faces, const VoxelSet& set,
                const Coverage& cover, std::vector<ColumnVoxel>* column,
                std::vector<uint64_t>* keys) {
  keys->clear();
  for (uint32_t f : faces) {
    ColumnOf(mesh, f, set, mesh.face_thickness_voxels[f] / 2, column);
    for (const ColumnVoxel& c : *column) {
      if (cover.Count(c) == 0) keys->push_back(c.id << 1 | uint64_t(c.in_set));
    }
  }
  std::sort(keys->begin(), keys->end());
  keys->erase(std::unique(keys->begin(), keys->end()), keys->end());
  int64_t gain = 0;
  for (uint64_t k : *keys) gain += (k & 1) ? 1 : -1;
  return gain;
}

void AddColumns(const TriangleMesh& mesh, std::span<const uint32_t> faces, const VoxelSet& set,
                int delta, Coverage* cover, std::vector<ColumnVoxel>* column) {
  for (uint32_t f : faces) {
    ColumnOf(mesh, f, set, mesh.face_thickness_voxels[f] / 2, column);
    for (const ColumnVoxel& c : *column) cover->Add(c, delta);
  }
}

}  // namespace

VertexFitStats FitVertexPositions(TriangleMesh* mesh_ptr, const VoxelSet& set,
                                  const VertexFitOptions& options) {
  TriangleMesh& mesh = *mesh_ptr;
  VertexFitStats stats;
  const size_t nv = mesh.vertices.size();
  if (mesh.face_thickness_voxels.size() != mesh.faces.size() || nv == 0) return stats;
  std::vector<std::vector<uint32_t>> faces_of(nv);
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    for (uint32_t v : mesh.faces[f]) faces_of[v].push_back(f);
  }
  std::vector<Vec3> start_normal(mesh.faces.size());
  std::vector<double> start_angle(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    start_normal[f] = UnitNormal(Corners(mesh, f));
    start_angle[f] = MinAngleDegrees(Corners(mesh, f));
  }
  // Edges by the faces that share them, in key order (sums must not follow a hash table's
  // order, which differs between processes): a junction's vertices stay; a rim edge moves
  // across the rim, away from its face in the face's plane.
  std::vector<std::pair<uint64_t, std::vector<uint32_t>>> edges;
  {
    absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edge_faces;
    for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
      const Face& t = mesh.faces[f];
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = std::min(t[k], t[(k + 1) % 3]), b = std::max(t[k], t[(k + 1) % 3]);
        edge_faces[uint64_t(a) << 32 | b].push_back(f);
      }
    }
    edges.assign(edge_faces.begin(), edge_faces.end());
    std::sort(edges.begin(), edges.end());
  }
  std::vector<uint8_t> fixed(nv, 0);
  struct RimEdge {
    uint32_t a, b;
    Vec3 out;
  };
  std::vector<RimEdge> rim;
  std::vector<Vec3> out_of(nv);  // across the rim at a vertex: its rim edges' directions
  for (const auto& [key, fs] : edges) {
    const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
    if (fs.size() >= 3) fixed[a] = fixed[b] = 1;
    if (fs.size() != 1) continue;
    const Face& t = mesh.faces[fs[0]];
    const uint32_t x = t[0] != a && t[0] != b ? t[0] : (t[1] != a && t[1] != b ? t[1] : t[2]);
    Vec3 m = Normalized(Cross(mesh.vertices[b] - mesh.vertices[a], start_normal[fs[0]]));
    if (Dot(m, mesh.vertices[a] - mesh.vertices[x]) < 0) m = -m;
    rim.push_back({a, b, m});
    out_of[a] += m;
    out_of[b] += m;
  }
  edges = {};
  // Beside a junction too (`junction_rings` rings of faces): a vertex moved there narrows the wedge
  // between the sheets, which the volume mesh has to fill (measured: a 2° tetrahedron at DPM's
  // crossing).
  for (int ring = 0; ring < options.junction_rings; ++ring) {
    const std::vector<uint8_t> near = fixed;
    for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
      const Face& t = mesh.faces[f];
      if (near[t[0]] || near[t[1]] || near[t[2]]) {
        for (uint32_t v : t) fixed[v] = 1;
      }
    }
  }
  // Along the normal (mesh/vertex_normals); across the rim in the tangent plane.
  const std::vector<Vec3> normal_of = VertexNormals(mesh.vertices, mesh.faces);
  for (uint32_t v = 0; v < nv; ++v) {
    out_of[v] = Normalized(out_of[v] - normal_of[v] * Dot(out_of[v], normal_of[v]));
  }
  const Dims& d = set.dims();
  // The box's faces, where the outermost voxels end.
  const double lo = -0.5, hi[3] = {d.nx - 0.5, d.ny - 0.5, d.nz - 0.5};
  auto on_face = [&](double x, int i) { return x <= lo + 1e-6 || x >= hi[i] - 1e-6; };
  const std::vector<Vec3> start = mesh.vertices;
  // A coordinate in a face of the box stays there; otherwise no vertex comes within a voxel
  // of a face of the box (nearer than it started) — a rim grazing the box's face leaves
  // slivers between them in the volume mesh (measured: 0.13° on DPM at r = 3).
  auto InBox = [&](Vec3 p, uint32_t v) {
    const Vec3& here = mesh.vertices[v];
    for (int i = 0; i < 3; ++i) {
      if (on_face(here[i], i)) {
        p[i] = here[i];
      } else {
        const double s = start[v][i];
        p[i] = std::clamp(p[i], std::min(s, lo + 1), std::max(s, hi[i] - 1));
      }
    }
    return p;
  };
  const double cos_turn = std::cos(options.max_normal_turn * 3.14159265358979323846 / 180.0);

  Coverage cover(set);
  std::vector<ColumnVoxel> column;
  std::vector<uint64_t> keys;
  std::vector<uint32_t> faces(mesh.faces.size());
  for (uint32_t f = 0; f < faces.size(); ++f) faces[f] = f;
  AddColumns(mesh, faces, set, +1, &cover, &column);

  // Whether the faces keep within the bounds where they lie now.
  auto acceptable = [&](std::span<const uint32_t> fs) {
    for (uint32_t f : fs) {
      const Triangle t = Corners(mesh, f);
      const Vec3 n = AreaVector(t);
      const double len = Norm(n);
      if (!(len > 1e-9)) return false;
      if (Dot(n, start_normal[f]) < cos_turn * len) return false;
      if (MinAngleDegrees(t) < std::min(options.min_angle, start_angle[f])) return false;
    }
    return true;
  };
  // Of `candidates` (positions for the vertices `vs`, kMaxGroup at a time), the one that
  // gains most is taken (a tie too where `ties` holds); its gain, none when they stay.
  using Positions = std::array<Vec3, 2>;
  std::vector<Positions> candidates;
  auto try_positions = [&](std::span<const uint32_t> vs, bool ties) -> std::optional<int64_t> {
    if (candidates.empty()) return std::nullopt;
    faces.clear();
    for (uint32_t v : vs) faces.insert(faces.end(), faces_of[v].begin(), faces_of[v].end());
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    Positions here{};
    for (size_t k = 0; k < vs.size(); ++k) here[k] = mesh.vertices[vs[k]];
    AddColumns(mesh, faces, set, -1, &cover, &column);
    const int64_t base = OwnGain(mesh, faces, set, cover, &column, &keys);
    int64_t best = ties ? -1 : 0;
    const Positions* chosen = nullptr;
    for (const Positions& c : candidates) {
      for (size_t k = 0; k < vs.size(); ++k) mesh.vertices[vs[k]] = c[k];
      if (acceptable(faces)) {
        const int64_t gain = OwnGain(mesh, faces, set, cover, &column, &keys) - base;
        if (gain > best) {
          best = gain;
          chosen = &c;
        }
      }
    }
    for (size_t k = 0; k < vs.size(); ++k) mesh.vertices[vs[k]] = chosen ? (*chosen)[k] : here[k];
    AddColumns(mesh, faces, set, +1, &cover, &column);
    if (!chosen) return std::nullopt;
    return best;
  };
  // One or two steps along `dir` or against it.
  auto along = [&](std::span<const uint32_t> vs, const Vec3& dir) {
    candidates.clear();
    if (Norm2(dir) == 0) return;
    for (double s : {-2.0, -1.0, 1.0, 2.0}) {
      Positions c{};
      bool ok = true;
      for (size_t k = 0; k < vs.size(); ++k) {
        const Vec3 p = mesh.vertices[vs[k]] + dir * (s * options.step);
        ok = ok && Norm2(p - start[vs[k]]) <= options.max_offset * options.max_offset;
        c[k] = InBox(p, vs[k]);
      }
      if (ok) candidates.push_back(c);
    }
  };
  // A rim near a face of the box onto it: the coordinates within reach set to the face.
  auto onto_box = [&](std::span<const uint32_t> vs) {
    candidates.clear();
    Positions c{};
    bool any = false;
    for (size_t k = 0; k < vs.size(); ++k) {
      c[k] = mesh.vertices[vs[k]];
      for (int i = 0; i < 3; ++i) {
        const double x = c[k][i];
        if (on_face(x, i)) continue;
        if (x - lo <= options.box_reach) c[k][i] = lo, any = true;
        if (hi[i] - x <= options.box_reach) c[k][i] = hi[i], any = true;
      }
    }
    if (any) candidates.push_back(c);
  };

  // A vertex (or rim edge) is tried again only when a vertex of its faces moved in the pass
  // before.
  std::vector<uint8_t> dirty(nv, 1), next(nv, 0);
  auto moved = [&](std::span<const uint32_t> vs, int64_t gain) {
    ++stats.moves;
    stats.voxels_gained += gain;
    for (uint32_t v : vs) {
      for (uint32_t f : faces_of[v]) {
        for (uint32_t w : mesh.faces[f]) next[w] = 1;
      }
    }
  };
  for (int pass = 0; pass < options.passes; ++pass) {
    const uint64_t moves_before = stats.moves;
    std::fill(next.begin(), next.end(), 0);
    for (uint32_t v = 0; v < nv; ++v) {
      if (fixed[v] || faces_of[v].empty() || !dirty[v]) continue;
      ++stats.vertices_tried;
      const uint32_t vs[1] = {v};
      for (const Vec3& dir : {options.along_normal ? normal_of[v] : Vec3(), out_of[v]}) {
        along(vs, dir);
        if (const auto gain = try_positions(vs, false)) moved(vs, *gain);
      }
      if (Norm2(out_of[v]) > 0) {
        onto_box(vs);
        if (const auto gain = try_positions(vs, true)) moved(vs, *gain);
      }
    }
    // A straight rim short of the outline gains only when both ends of an edge move.
    for (const RimEdge& e : rim) {
      if (fixed[e.a] || fixed[e.b] || !(dirty[e.a] || dirty[e.b])) continue;
      const uint32_t vs[2] = {e.a, e.b};
      along(vs, e.out);
      if (const auto gain = try_positions(vs, false)) moved(vs, *gain);
      onto_box(vs);
      if (const auto gain = try_positions(vs, true)) moved(vs, *gain);
    }
    dirty.swap(next);
    if (stats.moves == moves_before) break;
  }
  return stats;
}

}  // namespace sheetmesh
