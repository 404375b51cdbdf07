#include "worker/pipeline/surface/mid_surface.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <tuple>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/surface/mid_surface_box.h"
#include "worker/pipeline/surface/mid_surface_chart.h"
#include "worker/pipeline/surface/mid_surface_junctions.h"
#include "worker/pipeline/voxel/components.h"

namespace sheetmesh {
namespace {

constexpr double kPi = 3.14159265358979323846;

uint64_t Key(int32_t i, int32_t j) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(i)) << 32) | static_cast<uint32_t>(j);
}

// Coordinates of a voxel in the frame of `axis`: the other two in cyclic order (so that
// (i, j, h) is right-handed), then the axis'.
ChartVoxel InFrame(const Index3& p, int axis) {
  const int32_t c[3] = {p.x, p.y, p.z};
  return {c[(axis + 1) % 3], c[(axis + 2) % 3], c[axis]};
}

Vec3 FromFrame(double i, double j, double h, int axis) {
  double c[3];
  c[(axis + 1) % 3] = i;
  c[(axis + 2) % 3] = j;
  c[axis] = h;
  return Vec3(c[0], c[1], c[2]);
}

// The plane of least squares through a piece's voxels.
void FitPlane(const std::vector<Index3>& voxels, Vec3* centroid, Vec3* normal) {
  std::vector<Vec3> points;
  points.reserve(voxels.size());
  for (const Index3& p : voxels) points.emplace_back(p.x, p.y, p.z);
  FitPlanePoints(points, centroid, normal);
}

// Sheets stacked in one piece — two that cross at a shallow angle (the separation's folds
// do not see 15 degrees), or a sheet and one running along it — are layers of its columns:
// along the piece's axis a column holds one run of each. Runs of neighbouring columns that
// touch are one layer; a run that touches two runs of one neighbouring column, or is much
// longer than a run it touches (where two layers merge), joins layers and is left out:
// the layers apart are the pieces. Returns the layers of at least `min_voxels` (the piece
// itself when it has one), and in *junction the voxels left out.
//
// The layers are taken along `axis`; *clean counts the voxels of kept layers in columns
// where their layer has one run (what a chart of each can mesh).
std::vector<std::vector<Index3>> SplitLayers(std::vector<Index3> voxels, int axis,
                                             uint64_t min_voxels, std::vector<Index3>* junction,
                                             uint64_t* clean) {
  std::vector<ChartVoxel> v(voxels.size());
  for (size_t k = 0; k < voxels.size(); ++k) v[k] = InFrame(voxels[k], axis);
  std::sort(v.begin(), v.end());
  struct Run {
    int32_t i, j, lo, hi;
    size_t first;  // in v
  };
  std::vector<Run> runs;
  absl::flat_hash_map<uint64_t, std::pair<uint32_t, uint32_t>> column;  // -> runs [a, b)
  for (size_t s = 0; s < v.size();) {
    size_t q = s + 1;
    while (q < v.size() && v[q].i == v[s].i && v[q].j == v[s].j && v[q].h == v[q - 1].h + 1) ++q;
    const uint64_t key = Key(v[s].i, v[s].j);
    auto [it, fresh] = column.try_emplace(key, static_cast<uint32_t>(runs.size()),
                                          static_cast<uint32_t>(runs.size()));
    it->second.second = static_cast<uint32_t>(runs.size() + 1);
    runs.push_back({v[s].i, v[s].j, v[s].h, v[q - 1].h, s});
    s = q;
  }
  // Runs far longer than the piece's are not a height field's: a sheet standing across the
  // axis (a steep crossing) lies along them.
  std::vector<int32_t> lengths;
  for (const Run& r : runs) lengths.push_back(r.hi - r.lo + 1);
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  const int32_t longest_clean = 3 * lengths[lengths.size() / 2] + 2;
  auto clean_run = [&](const Run& r) {
    const int32_t l = r.hi - r.lo + 1;
    return l <= longest_clean ? l : 0;
  };
  // A single layer: nothing to split (most pieces).
  uint64_t stacked = 0;
  for (const auto& [key, range] : column) stacked += range.second - range.first > 1;
  if (stacked < std::max<uint64_t>(16, column.size() / 50)) {
    *clean = 0;
    for (const auto& [key, range] : column) {
      if (range.second - range.first == 1) *clean += clean_run(runs[range.first]);
    }
    return {std::move(voxels)};
  }
  auto length = [&](uint32_t r) { return runs[r].hi - runs[r].lo + 1; };
  std::vector<uint8_t> joins(runs.size(), 0);
  std::vector<std::pair<uint32_t, uint32_t>> touching;
  // The shortest run each run touches in a neighbouring column: a run much longer than that
  // is where two layers run together (a steep sheet's runs are all long, and stay whole).
  std::vector<int32_t> shortest_beside(runs.size(), INT32_MAX);
  for (uint32_t r = 0; r < runs.size(); ++r) {
    const Run& a = runs[r];
    for (const auto& [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const auto it = column.find(Key(a.i + di, a.j + dj));
      if (it == column.end()) continue;
      int touches = 0;
      for (uint32_t o = it->second.first; o < it->second.second; ++o) {
        const Run& b = runs[o];
        if (b.lo > a.hi + 1 || b.hi < a.lo - 1) continue;
        ++touches;
        shortest_beside[r] = std::min(shortest_beside[r], length(o));
        if (r < o) touching.push_back({r, o});
      }
      if (touches > 1) joins[r] = 1;
    }
  }
  for (uint32_t r = 0; r < runs.size(); ++r) {
    if (shortest_beside[r] != INT32_MAX && length(r) > 1.6 * shortest_beside[r] + 1) joins[r] = 1;
  }
  std::vector<uint32_t> parent(runs.size());
  for (uint32_t r = 0; r < runs.size(); ++r) parent[r] = r;
  const std::function<uint32_t(uint32_t)> find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& [a, b] : touching) {
    if (!joins[a] && !joins[b]) parent[find(a)] = find(b);
  }
  // Where two layers merge over many columns (two sheets crossing at 15 degrees run together
  // for a dozen voxels), the merged runs make a layer of their own between the runs that
  // join: a layer that joins three others or more through them is the junction too.
  absl::flat_hash_map<uint32_t, uint64_t> layer_voxels;
  for (uint32_t r = 0; r < runs.size(); ++r) {
    if (!joins[r]) layer_voxels[find(r)] += runs[r].hi - runs[r].lo + 1;
  }
  absl::flat_hash_map<uint32_t, absl::flat_hash_set<uint32_t>> joined_to;
  {
    absl::flat_hash_map<uint32_t, std::vector<uint32_t>> layers_at_join;  // join run -> layers
    for (const auto& [a, b] : touching) {
      if (joins[a] == joins[b]) continue;
      const uint32_t join = joins[a] ? a : b, other = joins[a] ? b : a;
      if (layer_voxels[find(other)] >= min_voxels) layers_at_join[join].push_back(find(other));
    }
    for (const auto& [join, ls] : layers_at_join) {
      for (uint32_t x : ls) {
        for (uint32_t y : ls) {
          if (x != y) joined_to[x].insert(y);
        }
      }
    }
  }
  absl::flat_hash_map<uint32_t, std::vector<Index3>> layers;
  absl::flat_hash_map<std::pair<uint32_t, uint64_t>, uint32_t> runs_in_column;  // of a layer
  std::vector<uint8_t> junction_run(runs.size(), 0);
  for (uint32_t r = 0; r < runs.size(); ++r) {
    const auto j = joins[r] ? joined_to.end() : joined_to.find(find(r));
    junction_run[r] = joins[r] || (j != joined_to.end() && j->second.size() >= 3);
    if (!junction_run[r]) ++runs_in_column[{find(r), Key(runs[r].i, runs[r].j)}];
  }
  for (uint32_t r = 0; r < runs.size(); ++r) {
    const Run& run = runs[r];
    std::vector<Index3>& out = junction_run[r] ? *junction : layers[find(r)];
    for (int32_t h = run.lo; h <= run.hi; ++h) {
      const Vec3 p = FromFrame(run.i, run.j, h, axis);
      out.push_back(
          {static_cast<int32_t>(p.x), static_cast<int32_t>(p.y), static_cast<int32_t>(p.z)});
    }
  }
  std::vector<std::vector<Index3>> kept;
  *clean = 0;
  for (uint32_t r = 0; r < runs.size(); ++r) {
    if (!junction_run[r] && layers[find(r)].size() >= min_voxels &&
        runs_in_column[{find(r), Key(runs[r].i, runs[r].j)}] == 1) {
      *clean += clean_run(runs[r]);
    }
  }
  for (auto& [root, layer] : layers) {
    if (layer.size() >= min_voxels) {
      kept.push_back(std::move(layer));
    } else {
      junction->insert(junction->end(), layer.begin(), layer.end());
    }
  }
  if (kept.size() <= 1) {  // no two layers worth a chart each
    *clean = 0;
    for (const auto& [key, range] : column) {
      if (range.second - range.first == 1) *clean += clean_run(runs[range.first]);
    }
    junction->clear();
    return {std::move(voxels)};
  }
  // Largest first, ties by the first voxel: the same order every run.
  std::sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) {
    if (a.size() != b.size()) return a.size() > b.size();
    return std::tie(a[0].z, a[0].y, a[0].x) < std::tie(b[0].z, b[0].y, b[0].x);
  });
  return kept;
}

// A piece as the sheets a chart each can mesh: its layers along the axis of its plane, each
// split again the same way (three sheets), to a depth of 3. *clean (when given) is the share
// of the voxels not left to junctions that lie in columns of one run of their layer, runs no
// longer than a height field's.
std::vector<std::vector<Index3>> SplitPiece(std::vector<Index3> voxels, uint64_t min_voxels,
                                            std::vector<Index3>* junction, double* clean = nullptr,
                                            int depth = 0) {
  Vec3 centroid, normal;
  FitPlane(voxels, &centroid, &normal);
  const double n[3] = {std::abs(normal.x), std::abs(normal.y), std::abs(normal.z)};
  const int axis = static_cast<int>(std::max_element(n, n + 3) - n);
  const uint64_t all = voxels.size();
  const size_t junction_before = junction->size();
  uint64_t clean_voxels = 0;
  std::vector<std::vector<Index3>> layers =
      SplitLayers(std::move(voxels), axis, min_voxels, junction, &clean_voxels);
  if (clean != nullptr) {
    const uint64_t left = all - (junction->size() - junction_before);
    *clean = left == 0 ? 1.0 : static_cast<double>(clean_voxels) / left;
  }
  if (layers.size() <= 1 || depth >= 2) return layers;
  std::vector<std::vector<Index3>> out;
  for (std::vector<Index3>& layer : layers) {
    for (std::vector<Index3>& l :
         SplitPiece(std::move(layer), min_voxels, junction, nullptr, depth + 1)) {
      out.push_back(std::move(l));
    }
  }
  // Largest first, ties by the first voxel: the same order every run.
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    if (a.size() != b.size()) return a.size() > b.size();
    return std::tie(a[0].z, a[0].y, a[0].x) < std::tie(b[0].z, b[0].y, b[0].x);
  });
  return out;
}

uint64_t MinLayerVoxels(uint64_t piece_voxels) { return std::max<uint64_t>(64, piece_voxels / 50); }

}  // namespace

uint64_t FlattenAtJunctions(TriangleMesh* mesh, const std::vector<JunctionLine>& lines) {
  constexpr double kOnLine = 0.05;  // voxels: a vertex this near a line lies on it
  auto on = [&](const Vec3& p, const JunctionLine& l) {
    return l.Distance2(p) < kOnLine * kOnLine;
  };
  uint64_t moved = 0;
  std::vector<uint8_t> done(mesh->vertices.size(), 0);
  for (size_t f = 0; f < mesh->faces.size(); ++f) {
    const Face& t = mesh->faces[f];
    const int32_t piece = mesh->face_piece.empty() ? 0 : mesh->face_piece[f];
    for (const JunctionLine& l : lines) {
      // The face's edge on the line, and the corner off it.
      int off = -1, count = 0;
      for (int k = 0; k < 3; ++k) {
        if (on(mesh->vertices[t[k]], l)) {
          ++count;
        } else {
          off = k;
        }
      }
      if (count != 2 || off < 0 || done[t[off]]) continue;
      for (size_t c = 0; c < l.pieces.size(); ++c) {
        if (l.pieces[c] != piece) continue;
        Vec3& p = mesh->vertices[t[off]];
        const Vec3& n = l.plane_normals[c];
        p = p - n * Dot(p - l.plane_points[c], n);
        done[t[off]] = 1;
        ++moved;
      }
    }
  }
  return moved;
}

absl::StatusOr<std::vector<int32_t>> MidSurfacePieces(
    const VoxelSet& set, std::span<const int32_t> pieces,
    const std::function<absl::StatusOr<std::vector<int32_t>>()>& separate) {
  constexpr double kClean = 0.95;
  const double kShallow = std::cos(20 * kPi / 180);
  int32_t count = 0;
  for (int32_t p : pieces) count = std::max(count, p + 1);
  std::vector<std::vector<Index3>> voxels(count);
  set.ForEachVoxel([&](uint64_t index, int32_t x, int32_t y, int32_t z) {
    if (pieces[index] >= 0) voxels[pieces[index]].push_back({x, y, z});
  });
  std::vector<uint8_t> clean(count, 1);
  for (int32_t p = 0; p < count; ++p) {
    if (voxels[p].size() < 3) continue;
    std::vector<Index3> junction;
    double share = 1;
    const uint64_t piece_voxels = voxels[p].size();
    const uint64_t min_layer = MinLayerVoxels(piece_voxels);
    const std::vector<std::vector<Index3>> layers =
        SplitPiece(std::move(voxels[p]), min_layer, &junction, &share);
    // A piece whose layers leave a third of its voxels to their junctions (a sheet standing
    // across the axis, all long runs) is not a height field there, however clean the rest.
    clean[p] = share >= kClean && 3 * junction.size() <= piece_voxels;
    // Layers whose planes differ by more than a shallow crossing: separation sees their folds.
    std::vector<Vec3> normals;
    for (const std::vector<Index3>& layer : layers) {
      Vec3 c, n;
      FitPlane(layer, &c, &n);
      for (const Vec3& m : normals) clean[p] &= std::abs(Dot(m, n)) >= kShallow;
      normals.push_back(n);
    }
  }
  std::vector<int32_t> out(pieces.begin(), pieces.end());
  if (std::all_of(clean.begin(), clean.end(), [](uint8_t c) { return c; })) return out;
  SM_ASSIGN_OR_RETURN(const std::vector<int32_t> separated, separate());
  // Separation's small pieces (flat cells cut off beside a junction) are the junction's: a
  // chart of them would lie over the sheet beside them once that is filled up to the line.
  std::vector<uint64_t> component_size(count, 0);
  absl::flat_hash_map<std::pair<int32_t, int32_t>, uint64_t> part_size;
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i] < 0 || clean[out[i]]) continue;
    ++component_size[out[i]];
    if (separated[i] >= 0) ++part_size[{out[i], separated[i]}];
  }
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i] < 0 || clean[out[i]]) continue;
    const bool small = separated[i] < 0 ||
                       part_size[{out[i], separated[i]}] < MinLayerVoxels(component_size[out[i]]);
    out[i] = small ? -1 : count + separated[i];
  }
  return out;
}

absl::StatusOr<MidSurface> BuildMidSurface(const VoxelSet& set,
                                           std::span<const int32_t> piece_of_voxel,
                                           const Progress& progress) {
  if (!piece_of_voxel.empty() && piece_of_voxel.size() != set.size()) {
    return absl::InvalidArgumentError(absl::StrCat("mid-surface: ", piece_of_voxel.size(),
                                                   " piece labels for ", set.size(), " voxels"));
  }
  std::vector<int32_t> labels;
  if (piece_of_voxel.empty()) {
    SM_ASSIGN_OR_RETURN(const Components comps, LabelComponents(set, Connectivity::k6));
    const std::vector<uint32_t> l = comps.VoxelLabels(set);
    labels.assign(l.begin(), l.end());
    piece_of_voxel = labels;
  }
  int32_t pieces = 0;
  for (int32_t p : piece_of_voxel) pieces = std::max(pieces, p + 1);
  std::vector<std::vector<Index3>> voxels(pieces);
  std::vector<Index3> unlabelled;
  set.ForEachVoxel([&](uint64_t index, int32_t x, int32_t y, int32_t z) {
    const int32_t p = piece_of_voxel[index];
    (p >= 0 ? voxels[p] : unlabelled).push_back({x, y, z});
  });
  MidSurface out;
  int32_t next_piece = pieces;
  std::vector<std::unique_ptr<Chart>> charts;
  for (int32_t p = 0; p < pieces; ++p) {
    SM_RETURN_IF_ERROR(progress.Update(0.5 * p / std::max(1, pieces)));
    if (voxels[p].size() < 3) continue;
    const uint64_t min_layer = MinLayerVoxels(voxels[p].size());
    std::vector<std::vector<Index3>> layers =
        SplitPiece(std::move(voxels[p]), min_layer, &out.junction_voxels);
    for (size_t k = 0; k < layers.size(); ++k) {
      // The first layer keeps the piece's id; the others are new pieces.
      charts.push_back(
          std::make_unique<Chart>(std::move(layers[k]), k == 0 ? p : next_piece++, set.dims()));
    }
  }
  // Voxels in no chart: labelled none, and the runs the charts did not keep.
  for (const Index3& v : unlabelled) out.junction_voxels.push_back(v);
  out.junctions =
      JoinCharts(&charts, out.junction_voxels, set.dims(), JunctionOptions{}, &next_piece);
  SM_RETURN_IF_ERROR(progress.Update(0.7));
  for (const std::unique_ptr<Chart>& chart : charts) {
    chart->Mesh(&out.junctions, &out.mesh);
    out.charts.push_back(chart->info());
  }
  ClipMeshToBox(set.dims(), &out.junctions, &out.mesh);
  TriangleMesh& m = out.mesh;
  m.face_thickness_voxels.resize(m.faces.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    float t = 0;
    for (uint32_t v : m.faces[f]) t += m.vertex_thickness_voxels[v];
    m.face_thickness_voxels[f] = t / 3;
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
