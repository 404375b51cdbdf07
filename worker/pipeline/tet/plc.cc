#include "worker/pipeline/tet/plc.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <set>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/status_macros.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

// Face k of the box: axis k / 2, low side when k is even.
int Axis(int face) { return face / 2; }
bool Low(int face) { return face % 2 == 0; }

struct SheetTriangles {
  std::vector<Face> faces;
  std::vector<uint32_t> source;  // input face
  std::vector<int32_t> piece;
  std::vector<float> thickness;
};

// `s` without the triangles marked in `drop`.
SheetTriangles Without(const SheetTriangles& s, const std::vector<uint8_t>& drop) {
  SheetTriangles keep;
  for (size_t f = 0; f < s.faces.size(); ++f) {
    if (drop[f]) continue;
    keep.faces.push_back(s.faces[f]);
    keep.source.push_back(s.source[f]);
    keep.piece.push_back(s.piece[f]);
    keep.thickness.push_back(s.thickness[f]);
  }
  return keep;
}

// Improves the sheet triangles TetGen must keep, since a thin or flat triangle forces tiny
// tetrahedra and slivers around it: an edge between two triangles of one piece that are
// nearly coplanar (normals within max_fold) is flipped where that raises the smaller of
// the two triangles' smallest angles (Lawson's rule on the sheet). A flat triangle (largest
// angle over cap_degrees) has its long edge flipped whatever the fold, and where no flip
// applies and it has an edge on the sheet's rim it is dropped, as it covers almost nothing.
// No flip touches a `frozen` vertex. Returns the number of flips and drops.
std::pair<uint32_t, uint32_t> ImproveSheetTriangles(SheetTriangles& s, const std::vector<Vec3>& v,
                                                    const std::vector<uint8_t>& on_face,
                                                    const std::vector<uint8_t>& frozen,
                                                    double max_fold, double cap_degrees) {
  uint32_t flips = 0, drops = 0;
  auto corners = [&](const Face& f) { return Triangle{v[f[0]], v[f[1]], v[f[2]]}; };
  auto key = [](uint32_t a, uint32_t b) {
    return (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
  };
  for (int round = 0; round < 50; ++round) {
    absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edges;
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      for (int k = 0; k < 3; ++k) edges[key(s.faces[f][k], s.faces[f][(k + 1) % 3])].push_back(f);
    }
    std::vector<uint8_t> touched(s.faces.size(), 0), drop(s.faces.size(), 0);
    uint32_t changed = 0, dropped = 0;
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      if (touched[f]) continue;
      const auto [lo, hi] = AngleRangeDegrees(corners(s.faces[f]));
      // The edge opposite the largest angle: the one a flip or a drop would remove.
      int longest = 0;
      double best = -1;
      for (int k = 0; k < 3; ++k) {
        const double len = Norm(v[s.faces[f][(k + 1) % 3]] - v[s.faces[f][k]]);
        if (len > best) best = len, longest = k;
      }
      const uint32_t a = s.faces[f][longest], b = s.faces[f][(longest + 1) % 3],
                     c = s.faces[f][(longest + 2) % 3];
      const std::vector<uint32_t>& across = edges.at(key(a, b));
      // A flat triangle's plane is ill-defined, so the facet it makes cuts the sheet at an
      // arbitrary angle: inside the sheet its long edge is flipped whatever the fold (its
      // obtuse vertex lies nearly on that edge, and the flip trades it and its neighbour
      // for two halves of the neighbour); on the rim, where no flip applies, it is dropped,
      // as it covers almost nothing.
      const bool flat = hi > cap_degrees;
      auto drop_it = [&] {
        drop[f] = touched[f] = 1;
        ++drops;
        ++dropped;
        ++changed;
      };
      if (flat && across.size() == 1) {
        drop_it();
        continue;
      }
      // Flips the edge a-b shared with g, the other triangle on it; false where that is not
      // allowed or not better.
      auto flip = [&]() -> bool {
        if (across.size() != 2) return false;
        const uint32_t g = across[0] == f ? across[1] : across[0];
        if (touched[g] || s.piece[f] != s.piece[g]) return false;
        // g must run b -> a (consistent orientation); d is its third vertex.
        int kb = -1;
        for (int k = 0; k < 3; ++k) {
          if (s.faces[g][k] == b && s.faces[g][(k + 1) % 3] == a) kb = k;
        }
        if (kb < 0) return false;
        const uint32_t d = s.faces[g][(kb + 2) % 3];
        if (c == d || edges.contains(key(c, d)) || frozen[a] || frozen[b] || frozen[c] || frozen[d])
          return false;
        const Face nf = {a, d, c}, ng = {d, b, c};
        const Triangle tf = corners(s.faces[f]), tg = corners(s.faces[g]), tnf = corners(nf),
                       tng = corners(ng);
        if (!flat && AngleDegrees(AreaVector(tf), AreaVector(tg)) > max_fold) return false;
        if (AngleDegrees(AreaVector(tnf), AreaVector(tng)) > max_fold) return false;
        const Vec3 up = AreaVector(tf) + AreaVector(tg);
        if (Dot(AreaVector(tnf), up) <= 0 || Dot(AreaVector(tng), up) <= 0) return false;
        const double old_min = std::min(lo, AngleRangeDegrees(tg).first);
        const double new_min = std::min(AngleRangeDegrees(tnf).first, AngleRangeDegrees(tng).first);
        if (new_min < old_min + 0.5) return false;
        const bool in_box_face =
            (on_face[a] & on_face[d] & on_face[c]) || (on_face[d] & on_face[b] & on_face[c]);
        if (in_box_face) return false;
        const double af = Area(tf), ag = Area(tg);
        const float t = static_cast<float>((s.thickness[f] * af + s.thickness[g] * ag) /
                                           std::max(af + ag, 1e-300));
        s.faces[f] = nf;
        s.faces[g] = ng;
        s.thickness[f] = s.thickness[g] = t;
        touched[f] = touched[g] = 1;
        return true;
      };
      if (flip()) {
        ++flips;
        ++changed;
      } else if (flat && (edges.at(key(b, c)).size() == 1 || edges.at(key(c, a)).size() == 1)) {
        drop_it();
      }
    }
    if (dropped > 0) s = Without(s, drop);
    if (changed == 0) break;
  }
  return {flips, drops};
}

// Drops sheet triangles that lie on another sheet. Where part of one triangle comes within
// `gap` of another's interior while their planes are within max_degrees of parallel (they
// run alongside, not into each other), TetGen must fill the thin wedge between them with
// tetrahedra as thin as the gap, slivers that nothing after can mend. Of such a pair the
// one with more rim edges goes (ties: the smaller), if it has a rim edge at all: a fragment
// lying on a sheet, or a sheet's rim running over another sheet. Two interior triangles
// are left as they are, as dropping one would open a hole. Returns the number dropped.
uint32_t DropOverlaps(SheetTriangles& s, const std::vector<Vec3>& v, double gap,
                      double max_degrees) {
  constexpr int kSamples = 6;  // points per edge of the barycentric grid sampled
  const double max_sin = std::sin(max_degrees * std::numbers::pi / 180.0);
  auto corners = [&](uint32_t f) {
    return Triangle{v[s.faces[f][0]], v[s.faces[f][1]], v[s.faces[f][2]]};
  };
  // Whether some point of b lies within gap of a's plane and projects inside a (beyond
  // the vertices they share).
  auto near_interior = [&](uint32_t fa, uint32_t fb) {
    const Triangle a = corners(fa), b = corners(fb);
    const Vec3 n = AreaVector(a);
    const double n2 = Norm2(n);
    for (int i = 0; i <= kSamples; ++i)
      for (int j = 0; i + j <= kSamples; ++j) {
        const double u = static_cast<double>(i) / kSamples, w = static_cast<double>(j) / kSamples;
        const Vec3 p = b[0] + (b[1] - b[0]) * u + (b[2] - b[0]) * w;
        if (std::any_of(a.begin(), a.end(), [&](const Vec3& q) { return Norm2(p - q) < 1e-18; }))
          continue;
        // Barycentric coordinates of p's projection: signed areas against a's normal.
        const double l0 = Dot(Cross(a[1] - p, a[2] - p), n) / n2,
                     l1 = Dot(Cross(a[2] - p, a[0] - p), n) / n2, l2 = 1 - l0 - l1;
        if (l0 <= 1e-6 || l1 <= 1e-6 || l2 <= 1e-6) continue;
        if (std::abs(Dot(p - a[0], n)) < gap * std::sqrt(n2)) return true;
      }
    return false;
  };
  uint32_t dropped = 0;
  for (int round = 0; round < 20; ++round) {
    const size_t n = s.faces.size();
    // Rim edges per triangle (edges of one triangle only), areas, and bounding boxes grown
    // by the gap.
    std::vector<int> rim(n, 0);
    TriangleMesh faces_only;
    faces_only.faces = s.faces;
    const EdgeIndex edges(faces_only);
    for (const EdgeIndex::Edge& e : edges.edges()) {
      if (e.count == 1) ++rim[edges.faces(e)[0]];
    }
    std::vector<double> area(n);
    std::vector<Vec3> lo(n), hi(n);
    std::vector<uint32_t> order(n);
    for (uint32_t f = 0; f < n; ++f) {
      const Triangle t = corners(f);
      area[f] = Area(t);
      TriangleBox(t, gap, &lo[f], &hi[f]);
      order[f] = f;
    }
    // Sweep along x; pairs whose grown boxes meet on all three axes are tested.
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return lo[a].x < lo[b].x || (lo[a].x == lo[b].x && a < b);
    });
    std::vector<uint8_t> drop(n, 0);
    uint32_t count = 0;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t a = order[i];
      for (size_t j = i + 1; j < n && lo[order[j]].x <= hi[a].x; ++j) {
        const uint32_t b = order[j];
        if (drop[a] || drop[b]) continue;
        if (lo[b].y > hi[a].y || lo[a].y > hi[b].y || lo[b].z > hi[a].z || lo[a].z > hi[b].z)
          continue;
        // An edge shared (a fold there is the flips' business) or planes at an angle: no
        // overlap.
        int shared = 0;
        for (uint32_t x : s.faces[a])
          shared += x == s.faces[b][0] || x == s.faces[b][1] || x == s.faces[b][2];
        if (shared >= 2) continue;
        const Vec3 na = AreaVector(corners(a)), nb = AreaVector(corners(b));
        if (Norm(Cross(na, nb)) > max_sin * Norm(na) * Norm(nb)) continue;
        if (!near_interior(a, b) && !near_interior(b, a)) continue;
        const uint32_t loser =
            rim[a] != rim[b] ? (rim[a] > rim[b] ? a : b) : (area[a] <= area[b] ? a : b);
        if (rim[loser] == 0) continue;
        drop[loser] = 1;
        ++count;
      }
    }
    if (count == 0) break;
    s = Without(s, drop);
    dropped += count;
  }
  return dropped;
}

// Seed points for TetGen: a body-centred cubic (BCC) lattice, whose Delaunay
// tetrahedra all have dihedral angles of 60° and 90° and a radius aspect of 0.95, far
// better than the Delaunay refinement makes on its own. Level 0 has the given spacing
// and fills the space between kLatticeKeep spacings and kLatticeWidth further spacings
// from the sheets; each further level doubles the spacing and the band, so the mesh
// grades away from the sheets; the last level fills the rest. Points keep kLatticeKeep
// spacings of their level off the box faces. Near the sheets TetGen places the points,
// as the sheet triangles and their refinement decide.
//
// Each change of level leaves a layer of worse tetrahedra where the two spacings meet,
// and so does each box face, where the face's points meet the lattice's rows. The band
// is 2.5 spacings wide, not 2, so fewer levels meet within the box (radius aspect mean,
// DPM, `volume` path: 0.832 -> 0.845 for 11% more tetrahedra; bench/RESULTS.md). A level
// whose spacing is over a quarter of the box's thinnest side is not used (its finer
// neighbour fills the rest): between the margins on both sides it would have room for a
// row or two only, and the box's points and those rows, far apart, make poor tetrahedra
// across the whole thin side (NETL, 42 voxels thick: 0.826 -> 0.843).
constexpr double kLatticeKeep = 0.6;
constexpr double kLatticeWidth = 2.5;
constexpr int kLatticeLevels = 4;
constexpr double kLatticeFit = 4;  // a level's spacing fits this many times in the box

// Walks the seeding's levels, finest first: calls candidates(h, in_band) with level l's
// spacing h = spacing · 2^l, where in_band(p) tells whether p's distance to the sheets
// lies in that level's band.
template <class Candidates>
void ForEachLevel(const Plc& plc, double spacing, Candidates&& candidates) {
  std::vector<Triangle> tris;
  std::vector<Vec3> box_lo, box_hi;
  for (const Face& f : plc.sheet_triangles) {
    tris.push_back({plc.vertices[f[0]], plc.vertices[f[1]], plc.vertices[f[2]]});
    TriangleBox(tris.back(), 0.0, &box_lo.emplace_back(), &box_hi.emplace_back());
  }
  double inner = kLatticeKeep * spacing;  // where this level starts
  const Vec3 extent = plc.box_hi - plc.box_lo;
  const double thinnest = std::min({extent.x, extent.y, extent.z});
  int levels = kLatticeLevels;
  while (levels > 1 && kLatticeFit * spacing * std::ldexp(1.0, levels - 1) > thinnest) --levels;
  for (int level = 0; level < levels; ++level) {
    const double h = spacing * std::ldexp(1.0, level);
    const bool last = level + 1 == levels;
    const double outer = inner + kLatticeWidth * h;  // where it ends (not for the last)
    // Triangles near a point are found in a grid whose cells are as wide as the band's
    // outer edge, so a query touches at most 27 cells.
    SpatialGrid grid(outer);
    for (uint32_t t = 0; t < tris.size(); ++t) grid.Insert(t, box_lo[t], box_hi[t]);
    auto in_band = [&](const Vec3& p) {
      double near2 = std::numeric_limits<double>::infinity();
      const Vec3 r(outer, outer, outer);
      bool too_close = false;
      grid.Query(p - r, p + r, [&](uint32_t t) {
        if (too_close) return;
        near2 = std::min(near2, PointTriangleDistance2(p, tris[t]));
        too_close = near2 <= inner * inner;
      });
      if (too_close) return false;            // a finer level's, or TetGen's
      return last || near2 <= outer * outer;  // else a coarser level's
    };
    candidates(h, in_band);
    inner = outer;
  }
}

std::vector<Vec3> SeedLattice(const Plc& plc, double spacing) {
  std::vector<Vec3> seeds;
  const Vec3 lo = plc.box_lo, hi = plc.box_hi;
  ForEachLevel(plc, spacing, [&](double h, const auto& in_band) {
    const double margin = kLatticeKeep * h;
    auto take = [&](const Vec3& p) {
      for (int k = 0; k < 3; ++k) {
        if (p[k] < lo[k] + margin || p[k] > hi[k] - margin) return;
      }
      if (in_band(p)) seeds.push_back(p);
    };
    int64_t n[3];
    for (int k = 0; k < 3; ++k) n[k] = static_cast<int64_t>(std::floor((hi[k] - lo[k]) / h));
    for (int64_t z = 0; z <= n[2]; ++z) {
      for (int64_t y = 0; y <= n[1]; ++y) {
        for (int64_t x = 0; x <= n[0]; ++x) {
          const Vec3 corner(lo.x + x * h, lo.y + y * h, lo.z + z * h);
          take(corner);
          take(corner + Vec3(h / 2, h / 2, h / 2));
        }
      }
    }
  });
  return seeds;
}

// A point on the box's surface: on the faces whose bits are set (bit `face`, as on_face).
struct BoxPoint {
  Vec3 p;
  uint8_t on_face = 0;
};

// Points on the box's edges and faces for a TetGen that may add none there (-Y), graded
// like the lattice: on each edge, points every h of their level; on each face, rows h
// apart with every other row shifted by h/2 (triangles of angles near 63°, 63° and 53°),
// kept kLatticeKeep · h off the face's edges. Sheet traces keep their band free, as for
// the lattice.
std::vector<BoxPoint> SeedBox(const Plc& plc, double spacing) {
  std::vector<BoxPoint> points;
  const Vec3 lo = plc.box_lo, hi = plc.box_hi;
  ForEachLevel(plc, spacing, [&](double h, const auto& in_band) {
    const double margin = kLatticeKeep * h;
    for (int k = 0; k < 3; ++k) {
      const int a = (k + 1) % 3, b = (k + 2) % 3;
      // The 4 edges along axis k.
      for (int side = 0; side < 4; ++side) {
        Vec3 p = lo;
        p[a] = side & 1 ? hi[a] : lo[a];
        p[b] = side & 2 ? hi[b] : lo[b];
        const uint8_t bits =
            static_cast<uint8_t>((1 << (2 * a + (side & 1))) | (1 << (2 * b + (side & 2 ? 1 : 0))));
        for (int64_t i = 1;; ++i) {
          p[k] = lo[k] + i * h;
          if (p[k] > hi[k] - margin) break;
          if (p[k] >= lo[k] + margin && in_band(p)) points.push_back({p, bits});
        }
      }
      // The 2 faces across axis k: rows along a, stepping in b.
      for (int high = 0; high < 2; ++high) {
        Vec3 p;
        p[k] = high ? hi[k] : lo[k];
        const uint8_t bits = static_cast<uint8_t>(1 << (2 * k + high));
        for (int64_t j = 1;; ++j) {
          p[b] = lo[b] + j * h;
          if (p[b] > hi[b] - margin) break;
          for (int64_t i = 0;; ++i) {
            p[a] = lo[a] + (i + (j % 2 ? 0.5 : 0.0)) * h;
            if (p[a] > hi[a] - margin) break;
            if (p[a] >= lo[a] + margin && p[b] >= lo[b] + margin && in_band(p)) {
              points.push_back({p, bits});
            }
          }
        }
      }
    }
  });
  return points;
}

// Merges vertices within `merge` of an earlier one into it (snapping can bring vertices
// together): returns each vertex's representative; the faces a merged vertex lies on pass
// to its representative.
std::vector<uint32_t> MergeNearDuplicates(const std::vector<Vec3>& v, double merge,
                                          std::vector<uint8_t>* on_face, uint32_t* merged) {
  std::vector<uint32_t> rep(v.size());
  std::iota(rep.begin(), rep.end(), 0u);
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> cells;
  const double cell = std::max(merge, 1e-9) * 2;
  auto key = [&](int64_t x, int64_t y, int64_t z) {
    return (static_cast<uint64_t>(x & 0x1FFFFF) << 42) |
           (static_cast<uint64_t>(y & 0x1FFFFF) << 21) | static_cast<uint64_t>(z & 0x1FFFFF);
  };
  for (uint32_t i = 0; i < v.size(); ++i) {
    const int64_t cx = std::llround(v[i].x / cell), cy = std::llround(v[i].y / cell),
                  cz = std::llround(v[i].z / cell);
    bool found = false;
    for (int dz = -1; dz <= 1 && !found; ++dz)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dx = -1; dx <= 1 && !found; ++dx) {
          auto it = cells.find(key(cx + dx, cy + dy, cz + dz));
          if (it == cells.end()) continue;
          for (uint32_t j : it->second) {
            if (Norm(v[i] - v[j]) <= merge) {
              rep[i] = j;
              (*on_face)[j] |= (*on_face)[i];
              found = true;
              break;
            }
          }
        }
    if (found) {
      ++*merged;
    } else {
      cells[key(cx, cy, cz)].push_back(i);
    }
  }
  return rep;
}

// The sheets' triangles on the merged vertices that are still triangles and do not lie in
// a box face (each once).
SheetTriangles KeepTriangles(const TriangleMesh& sheets, const std::vector<Vec3>& v,
                             const std::vector<uint32_t>& rep, const std::vector<uint8_t>& on_face,
                             uint32_t* dropped) {
  SheetTriangles st;
  std::set<std::array<uint32_t, 3>> seen;
  for (size_t f = 0; f < sheets.faces.size(); ++f) {
    Face t = {rep[sheets.faces[f][0]], rep[sheets.faces[f][1]], rep[sheets.faces[f][2]]};
    std::array<uint32_t, 3> s = t;
    std::sort(s.begin(), s.end());
    const bool in_face = (on_face[t[0]] & on_face[t[1]] & on_face[t[2]]) != 0;
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || in_face || !seen.insert(s).second ||
        Area({v[t[0]], v[t[1]], v[t[2]]}) < 1e-9) {
      ++*dropped;
      continue;
    }
    st.faces.push_back(t);
    st.source.push_back(static_cast<uint32_t>(f));
    st.piece.push_back(sheets.face_piece.size() == sheets.faces.size() ? sheets.face_piece[f] : 0);
    st.thickness.push_back(
        sheets.face_thickness.size() == sheets.faces.size() ? sheets.face_thickness[f] : 0.f);
  }
  return st;
}

// ImproveSheetTriangles, kept only where it makes no clash: a flip moves the sheet a
// little, and where that makes it cut another sheet (near a crossing), the vertices of the
// clash are frozen and the improvement starts over. Returns the flips and drops kept.
std::pair<uint32_t, uint32_t> FlipSheetTriangles(SheetTriangles& st, const std::vector<Vec3>& v,
                                                 const std::vector<uint8_t>& on_face,
                                                 double fold_degrees, double cap_degrees) {
  std::vector<uint8_t> frozen(v.size(), 0);
  for (int attempt = 0; attempt < 5; ++attempt) {
    SheetTriangles better = st;
    const auto [flips, drops] =
        ImproveSheetTriangles(better, v, on_face, frozen, fold_degrees, cap_degrees);
    if (flips == 0 && drops == 0) break;
    TriangleMesh check;
    check.vertices = v;
    check.faces = better.faces;
    const auto clash = FindSelfIntersections(check, 1000, 1.0);
    if (clash.empty()) {
      st = std::move(better);
      return {flips, drops};
    }
    for (const auto& [a, b] : clash) {
      for (uint32_t x : better.faces[a]) frozen[x] = 1;
      for (uint32_t x : better.faces[b]) frozen[x] = 1;
    }
  }
  return {0, 0};
}

// Closes the slits in the sheets: three rim edges a-b, a-c, c-b that frame no triangle,
// with c nearly on a-b (its angle over min_degrees, as for a flat triangle). The face on
// a-b is split in two at c (unless a half would be flat too), so the rim runs a-c-b on both sides
// and the slit is gone. Left open, TetGen must fill the slit, flat as it is, with a sliver, and any
// point the improvement puts beside it lands a fraction of a voxel from c. Where a round's splits
// would make a clash, none of them is made. Returns the number of slits closed.
uint32_t CloseSlits(SheetTriangles& s, const std::vector<Vec3>& v, double min_degrees) {
  const double max_cos = std::cos(min_degrees * std::numbers::pi / 180.0);
  uint32_t closed = 0;
  for (int round = 0; round < 5; ++round) {
    TriangleMesh faces_only;
    faces_only.faces = s.faces;
    const EdgeIndex edges(faces_only);
    absl::flat_hash_map<uint32_t, std::vector<uint32_t>> rim;  // vertex -> rim neighbours
    for (const EdgeIndex::Edge& e : edges.edges()) {
      if (e.count != 1) continue;
      rim[e.a].push_back(e.b);
      rim[e.b].push_back(e.a);
    }
    SheetTriangles out = s;
    std::vector<uint8_t> split(s.faces.size(), 0);
    uint32_t count = 0;
    for (const EdgeIndex::Edge& e : edges.edges()) {
      if (e.count != 1) continue;
      const uint32_t f = edges.faces(e)[0];
      if (split[f]) continue;
      const Face face = s.faces[f];
      const auto& ra = rim[e.a];
      for (uint32_t c : rim[e.b]) {
        if (c == face[0] || c == face[1] || c == face[2]) continue;
        if (std::find(ra.begin(), ra.end(), c) == ra.end()) continue;
        const Vec3 ca = v[e.a] - v[c], cb = v[e.b] - v[c];
        const double la = Norm(ca), lb = Norm(cb);
        if (!(la > 0 && lb > 0) || !(Dot(ca, cb) < max_cos * la * lb)) continue;
        // Face (a, b, x) in its own order becomes (a, c, x) and (c, b, x).
        const int k = face[0] == e.a ? 0 : face[1] == e.a ? 1 : 2;
        const bool forward = face[(k + 1) % 3] == e.b;
        Face first = face, second = face;
        first[forward ? (k + 1) % 3 : (k + 2) % 3] = c;  // b -> c
        second[k] = c;                                   // a -> c
        // Neither half may be flat itself (c nearly on F's other edges too: F is a sliver).
        auto flat = [&](const Face& t) {
          return AngleRangeDegrees({v[t[0]], v[t[1]], v[t[2]]}).second > min_degrees;
        };
        if (flat(first) || flat(second)) continue;
        out.faces[f] = first;
        out.faces.push_back(second);
        out.source.push_back(s.source[f]);
        out.piece.push_back(s.piece[f]);
        out.thickness.push_back(s.thickness[f]);
        split[f] = 1;
        ++count;
        break;
      }
    }
    if (count == 0) break;
    TriangleMesh check;
    check.vertices = v;
    check.faces = out.faces;
    if (!FindSelfIntersections(check, 1, 1.0).empty()) break;
    s = std::move(out);
    closed += count;
  }
  return closed;
}

// Opens the narrow wedges between a sheet face and a sheet edge that leaves one of its
// corners just off its plane, over the face (the edge's direction, projected onto the
// plane, lies inside the face's angle at that corner). TetGen must fill such a wedge with
// tetrahedra whose dihedral angle there is about as small as the wedge, and nothing
// after can mend them without splitting the face many times over. The edge's far end
// moves straight away from the face's plane until the edge stands min_degrees off it, by
// at most max_move in all, and only where that opens the narrowest wedge around it and
// its neighbours; vertices on the box stay. A move that makes triangles clash is undone.
// Returns the number of vertices moved.
uint32_t OpenWedges(const SheetTriangles& st, const std::vector<uint8_t>& on_face,
                    double min_degrees, double max_move, std::vector<Vec3>& v) {
  if (!(min_degrees > 0) || !(max_move > 0) || st.faces.empty()) return 0;
  const double sin_min = std::sin(min_degrees * std::numbers::pi / 180.0);
  const double tan_min = std::tan(min_degrees * std::numbers::pi / 180.0);
  std::vector<std::vector<uint32_t>> faces_of(v.size());
  std::vector<std::vector<uint32_t>> next(v.size());
  for (uint32_t f = 0; f < st.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = st.faces[f][k];
      faces_of[a].push_back(f);
      for (int j = 1; j < 3; ++j) next[a].push_back(st.faces[f][(k + j) % 3]);
    }
  }
  for (auto& n : next) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  struct Wedge {
    double sine = 2;    // of the edge's angle to the face's plane
    uint32_t far = 0;   // the edge's far end
    double height = 0;  // of the far end over the face's plane (signed), and
    double length = 0;  // the edge's length
    Vec3 normal;        // the face's unit normal
  };
  // The narrowest wedge at corner u (sine 2: none).
  auto narrowest = [&](uint32_t u) {
    Wedge best;
    for (uint32_t f : faces_of[u]) {
      const Face& t = st.faces[f];
      const int k = t[0] == u ? 0 : t[1] == u ? 1 : 2;
      const Vec3 e1 = v[t[(k + 1) % 3]] - v[u], e2 = v[t[(k + 2) % 3]] - v[u];
      const Vec3 n = Cross(e1, e2);
      const double n2 = Norm2(n);
      if (!(n2 > 0)) continue;
      const Vec3 unit = n / std::sqrt(n2);
      for (uint32_t x : next[u]) {
        if (x == t[0] || x == t[1] || x == t[2]) continue;
        const Vec3 d = v[x] - v[u];
        const double len = Norm(d);
        if (!(len > 0)) continue;
        const double h = Dot(d, unit);
        // Inside the angle: d's projection is a positive combination of e1 and e2.
        if (!(Dot(Cross(e1, d), n) > 0 && Dot(Cross(d, e2), n) > 0)) continue;
        const double sine = std::abs(h) / len;
        if (sine < best.sine) best = {sine, x, h, len, unit};
      }
    }
    return best;
  };
  auto around = [&](uint32_t w) {
    double m = narrowest(w).sine;
    for (uint32_t x : next[w]) m = std::min(m, narrowest(x).sine);
    return m;
  };
  const std::vector<Vec3> original = v;
  std::vector<uint8_t> moved(v.size(), 0);
  for (int round = 0; round < 3; ++round) {
    bool any = false;
    for (uint32_t u = 0; u < v.size(); ++u) {
      if (faces_of[u].empty()) continue;
      const Wedge w = narrowest(u);
      if (!(w.sine < sin_min) || on_face[w.far] != 0) continue;
      const double before = around(w.far);
      // Moving along the normal keeps the edge's length in the plane.
      const double in_plane = std::sqrt(std::max(0.0, w.length * w.length - w.height * w.height));
      const double need = in_plane * tan_min - std::abs(w.height);
      const Vec3 start = v[w.far];
      Vec3 to = start + w.normal * ((w.height < 0 ? -1.0 : 1.0) * need);
      // At most max_move from where the vertex began.
      const Vec3 off = to - original[w.far];
      if (Norm(off) > max_move) to = original[w.far] + off * (max_move / Norm(off));
      v[w.far] = to;
      if (around(w.far) > before + 1e-9) {
        moved[w.far] = 1;
        any = true;
      } else {
        v[w.far] = start;
      }
    }
    if (!any) break;
  }
  // Undo the moves of vertices in clashing triangles, until none clash.
  for (int round = 0; round < 8; ++round) {
    TriangleMesh check;
    check.vertices = v;
    check.faces = st.faces;
    const auto clash = FindSelfIntersections(check, 1000, 1.0);
    if (clash.empty()) break;
    bool undone = false;
    for (const auto& [a, b] : clash) {
      for (const uint32_t f : {a, b}) {
        for (uint32_t x : st.faces[f]) {
          if (!moved[x]) continue;
          v[x] = original[x];
          moved[x] = 0;
          undone = true;
        }
      }
    }
    if (!undone) break;
  }
  return static_cast<uint32_t>(std::count(moved.begin(), moved.end(), 1));
}

}  // namespace

nlohmann::json PlcStats::Fields() const {
  return {{"snapped_vertices", snapped_vertices},
          {"snap_held_vertices", snap_held_vertices},
          {"merged_vertices", merged_vertices},
          {"dropped_triangles", dropped_triangles},
          {"repaired_triangles", repaired_triangles},
          {"flipped_edges", flipped_edges},
          {"dropped_caps", dropped_caps},
          {"dropped_overlaps", dropped_overlaps},
          {"closed_slits", closed_slits},
          {"opened_wedges", opened_wedges},
          {"box_points", box_points},
          {"seed_points", seed_points},
          {"lattice_spacing", lattice_spacing}};
}

std::string Plc::ToPoly() const {
  std::string out = absl::StrCat("# sheetmesh PLC: box + ", sheet_triangles.size(),
                                 " sheet triangles\n", vertices.size(), " 3 0 0\n");
  for (size_t i = 0; i < vertices.size(); ++i) {
    absl::StrAppendFormat(&out, "%d %.17g %.17g %.17g\n", i, vertices[i].x, vertices[i].y,
                          vertices[i].z);
  }
  absl::StrAppend(&out, facets.size(), " 1\n");
  for (const PlcFacet& f : facets) {
    absl::StrAppend(&out, f.polygons.size(), " 0 ", f.marker, "\n");
    for (const auto& poly : f.polygons) {
      out += std::to_string(poly.size());
      for (uint32_t v : poly) absl::StrAppend(&out, " ", v);
      out += "\n";
    }
  }
  out += "0\n0\n";
  return out;
}

absl::StatusOr<Plc> BuildPlc(const TriangleMesh& sheets, const Dims& dims,
                             const Placement& placement, const PlcOptions& options,
                             std::vector<Clash>* clashes) {
  if (dims.nx <= 0 || dims.ny <= 0 || dims.nz <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("volume mesh box ", dims.ToString(), " is empty"));
  }
  Plc plc;
  // The box spans the voxels' extent, in index coordinates [-0.5, n - 0.5].
  const Vec3 lo(-0.5, -0.5, -0.5), hi(dims.nx - 0.5, dims.ny - 0.5, dims.nz - 0.5);
  plc.box_lo = placement.ToPhysical(lo);
  plc.box_hi = placement.ToPhysical(hi);

  // Snap vertices onto box faces; note which faces each lies on. Vertices within
  // snap_voxels always snap; those out to snap_clear_voxels snap unless that makes their
  // triangles cut another sheet's (then they stay, and everything after is redone).
  std::vector<Vec3> v;
  std::vector<uint8_t> on_face;  // bit k: on box face k
  std::vector<uint32_t> rep;
  SheetTriangles st;
  std::vector<uint8_t> hold(sheets.vertices.size(), 0);  // kept off the box at the wider reach
  const double reach = std::max(options.snap_voxels, options.snap_clear_voxels);
  bool checked_clean = false;  // the last round's triangles were found not to clash
  for (int attempt = 0;; ++attempt) {
    plc.snapped_vertices = plc.merged_vertices = plc.dropped_triangles = 0;
    plc.flipped_edges = plc.dropped_caps = 0;
    plc.snap_held_vertices = static_cast<uint32_t>(std::count(hold.begin(), hold.end(), 1));
    std::vector<uint8_t> wide(sheets.vertices.size(), 0);  // snapped from beyond snap_voxels
    v = sheets.vertices;
    on_face.assign(v.size(), 0);
    for (size_t i = 0; i < v.size(); ++i) {
      const double limit = hold[i] ? options.snap_voxels : reach;
      bool moved = false;
      for (int k = 0; k < 3; ++k) {
        const double below = v[i][k] - lo[k], above = hi[k] - v[i][k];
        if (below < limit) {
          moved |= v[i][k] != lo[k];
          wide[i] |= below >= options.snap_voxels;
          v[i][k] = lo[k];
          on_face[i] |= 1 << (2 * k);
        } else if (above < limit) {
          moved |= v[i][k] != hi[k];
          wide[i] |= above >= options.snap_voxels;
          v[i][k] = hi[k];
          on_face[i] |= 1 << (2 * k + 1);
        }
      }
      plc.snapped_vertices += moved;
    }
    rep = MergeNearDuplicates(v, options.merge_voxels, &on_face, &plc.merged_vertices);
    st = KeepTriangles(sheets, v, rep, on_face, &plc.dropped_triangles);
    if (options.flip_fold_degrees > 0) {
      std::tie(plc.flipped_edges, plc.dropped_caps) =
          FlipSheetTriangles(st, v, on_face, options.flip_fold_degrees, options.cap_degrees);
    }
    if (attempt == 4 || std::none_of(wide.begin(), wide.end(), [](uint8_t w) { return w; })) {
      break;
    }
    TriangleMesh check;
    check.vertices = v;
    check.faces = st.faces;
    const auto clash = FindSelfIntersections(check, 1000, 1.0);
    checked_clean = clash.empty();
    if (checked_clean) break;
    // Hold back the widely snapped vertices (and those merged into them) of the clashing
    // triangles; a clash none of them is in stays, for the check below to report.
    absl::flat_hash_set<uint32_t> in_clash;
    for (const auto& [a, b] : clash) {
      in_clash.insert(st.faces[a].begin(), st.faces[a].end());
      in_clash.insert(st.faces[b].begin(), st.faces[b].end());
    }
    bool held = false;
    for (uint32_t i = 0; i < v.size(); ++i) {
      if (wide[i] && in_clash.contains(rep[i])) {
        hold[i] = 1;
        held = true;
      }
    }
    if (!held) break;
  }
  TriangleMesh kept;
  kept.faces = st.faces;
  kept.vertices = v;
  const std::vector<uint32_t>& source = st.source;

  // Facets must not cut through each other: check before TetGen (unless the snapping just
  // did), and name the clashes.
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  if (!checked_clean) pairs = FindSelfIntersections(kept, 10000, 1.0);
  if (!pairs.empty()) {
    if (clashes != nullptr) {
      for (const auto& [a, b] : pairs) {
        Clash c{source[a], source[b], Corners(kept, a), Corners(kept, b)};
        for (Vec3& p : c.ta) p = placement.ToPhysical(p);
        for (Vec3& p : c.tb) p = placement.ToPhysical(p);
        clashes->push_back(c);
      }
    }
    if (!options.repair) {
      std::string list;
      for (size_t i = 0; i < pairs.size() && i < 5; ++i) {
        const auto [a, b] = pairs[i];
        const Triangle ta = Corners(kept, a), tb = Corners(kept, b);
        auto fmt = [&](const Triangle& t) {
          std::string s;
          for (const Vec3& p0 : t) {
            const Vec3 p = placement.ToPhysical(p0);
            absl::StrAppendFormat(&s, "(%.4g,%.4g,%.4g)", p.x, p.y, p.z);
          }
          return s;
        };
        absl::StrAppendFormat(&list, "; triangles %d %s and %d %s", source[a], fmt(ta), source[b],
                              fmt(tb));
      }
      return absl::FailedPreconditionError(
          absl::StrCat(pairs.size(), " pairs of sheet triangles intersect", list,
                       pairs.size() > 5 ? "; ..." : "",
                       " (the repair option removes the smaller of each pair)"));
    }
    // Repair: drop the smaller triangle of each clashing pair.
    std::vector<uint8_t> drop(kept.faces.size(), 0);
    for (const auto& [a, b] : pairs) {
      if (drop[a] || drop[b]) continue;
      drop[Area(Corners(kept, a)) < Area(Corners(kept, b)) ? a : b] = 1;
    }
    st = Without(st, drop);
    plc.repaired_triangles = static_cast<uint32_t>(kept.faces.size() - st.faces.size());
    kept.faces = st.faces;
    if (!FindSelfIntersections(kept, 1, 1.0).empty()) {
      return absl::FailedPreconditionError(
          absl::StrCat("sheet triangles still intersect after removing ", plc.repaired_triangles,
                       " clashing ones; the intersections are not simple"));
    }
  }
  if (options.cap_degrees < 180) {
    plc.closed_slits = CloseSlits(st, v, options.cap_degrees);
    kept.faces = st.faces;
  }
  if (options.overlap_voxels > 0) {
    plc.dropped_overlaps = DropOverlaps(st, v, options.overlap_voxels, options.overlap_degrees);
    kept.faces = st.faces;
  }

  if (options.wedge_degrees > 0 && options.wedge_voxels > 0) {
    plc.opened_wedges = OpenWedges(st, on_face, options.wedge_degrees, options.wedge_voxels, v);
    kept.vertices = v;
  }

  // Compact the used vertices; the 8 box corners go first.
  std::vector<uint32_t> index(v.size(), UINT32_MAX);
  for (int c = 0; c < 8; ++c) {
    plc.vertices.push_back(
        placement.ToPhysical(Vec3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z)));
  }
  for (const Face& t : kept.faces) {
    Face out;
    for (int k = 0; k < 3; ++k) {
      if (index[t[k]] == UINT32_MAX) {
        index[t[k]] = static_cast<uint32_t>(plc.vertices.size());
        plc.vertices.push_back(placement.ToPhysical(v[t[k]]));
      }
      out[k] = index[t[k]];
    }
    const size_t f = plc.sheet_triangles.size();
    plc.sheet_triangles.push_back(out);
    plc.sheet_piece.push_back(st.piece[f]);
    plc.sheet_thickness.push_back(st.thickness[f]);
  }
  // The sheets' median edge sets the spacing of the seeded points, so that the tetrahedra
  // off the sheets are about as large as those on them.
  double median_edge = 0;
  if (!plc.sheet_triangles.empty()) {
    std::vector<double> edges;
    for (const Face& f : plc.sheet_triangles) {
      for (int k = 0; k < 3; ++k)
        edges.push_back(Norm(plc.vertices[f[(k + 1) % 3]] - plc.vertices[f[k]]));
    }
    std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
    median_edge = edges[edges.size() / 2];
  }
  // Points of the box's surface, when TetGen may add none there.
  std::vector<BoxPoint> box_points;
  const uint32_t first_box_point = static_cast<uint32_t>(plc.vertices.size());
  if (options.seed_box && median_edge > 0) {
    box_points = SeedBox(plc, (options.lattice > 0 ? options.lattice : 1.0) * median_edge);
    for (const BoxPoint& b : box_points) plc.vertices.push_back(b.p);
    plc.box_points = static_cast<uint32_t>(box_points.size());
  }
  // Box faces. Corner c has bit 0 = x high, bit 1 = y high, bit 2 = z high. Each face is a
  // polygon through its 4 corners and the sheet vertices on its edges, in order, plus the
  // sheet edges and vertices that lie in it.
  for (int face = 0; face < 6; ++face) {
    const int k = Axis(face);
    const int bit = Low(face) ? 0 : 1;
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    // Corners of the face in cyclic order over axes a, b.
    auto corner = [&](int ca, int cb) {
      int c = 0;
      if (bit) c |= 1 << k;
      if (ca) c |= 1 << a;
      if (cb) c |= 1 << b;
      return static_cast<uint32_t>(c);
    };
    const uint32_t cyc[4] = {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
    std::vector<uint32_t> polygon;
    for (int e = 0; e < 4; ++e) {
      const uint32_t p = cyc[e], q = cyc[(e + 1) % 4];
      polygon.push_back(p);
      // Sheet vertices on edge p-q: on this face and on the face of the other varying axis.
      std::vector<std::pair<double, uint32_t>> along;
      const Vec3 pp = plc.vertices[p], qq = plc.vertices[q];
      const Vec3 dir = qq - pp;
      for (uint32_t i = 0; i < v.size(); ++i) {
        if (index[i] == UINT32_MAX || !(on_face[i] & (1 << face))) continue;
        const Vec3 x = placement.ToPhysical(v[i]);
        const double t = Dot(x - pp, dir) / Norm2(dir);
        if (t <= 1e-12 || t >= 1 - 1e-12) continue;
        if (Norm(x - (pp + dir * t)) > 1e-9 * (1 + Norm(dir))) continue;
        along.emplace_back(t, index[i]);
      }
      for (uint32_t i = 0; i < box_points.size(); ++i) {
        const BoxPoint& bp = box_points[i];
        if (!(bp.on_face & (1 << face)) || std::popcount(bp.on_face) != 2) continue;
        const double t = Dot(bp.p - pp, dir) / Norm2(dir);
        if (t <= 1e-12 || t >= 1 - 1e-12) continue;
        if (Norm(bp.p - (pp + dir * t)) > 1e-9 * (1 + Norm(dir))) continue;
        along.emplace_back(t, first_box_point + i);
      }
      std::sort(along.begin(), along.end());
      for (const auto& [t, id] : along) polygon.push_back(id);
    }
    PlcFacet facet;
    facet.marker = kBoundaryMarker;
    facet.polygons.push_back(polygon);
    std::set<uint32_t> on_polygon(polygon.begin(), polygon.end());
    std::set<std::pair<uint32_t, uint32_t>> segments;
    std::set<uint32_t> points;
    for (size_t f = 0; f < kept.faces.size(); ++f) {
      const Face& t = kept.faces[f];
      for (int e = 0; e < 3; ++e) {
        const uint32_t s = t[e], u = t[(e + 1) % 3];
        if ((on_face[s] & on_face[u] & (1 << face)) != 0) {
          segments.insert({std::min(index[s], index[u]), std::max(index[s], index[u])});
        }
      }
      for (uint32_t s : t) {
        if ((on_face[s] & (1 << face)) && !on_polygon.count(index[s])) points.insert(index[s]);
      }
    }
    for (const auto& [s, u] : segments) {
      if (on_polygon.count(s) && on_polygon.count(u)) continue;  // lies on the outline
      facet.polygons.push_back({s, u});
      points.erase(s);
      points.erase(u);
    }
    for (uint32_t p : points) facet.polygons.push_back({p});
    for (uint32_t i = 0; i < box_points.size(); ++i) {
      if (box_points[i].on_face == (1 << face)) facet.polygons.push_back({first_box_point + i});
    }
    plc.facets.push_back(std::move(facet));
  }
  for (size_t t = 0; t < plc.sheet_triangles.size(); ++t) {
    const Face& f = plc.sheet_triangles[t];
    plc.facets.push_back({{{f[0], f[1], f[2]}}, kFirstSheetMarker + static_cast<int32_t>(t)});
  }
  if (options.lattice > 0 && median_edge > 0) {
    plc.lattice_spacing = options.lattice * median_edge;
    const std::vector<Vec3> seeds = SeedLattice(plc, plc.lattice_spacing);
    plc.seed_points = static_cast<uint32_t>(seeds.size());
    plc.vertices.insert(plc.vertices.end(), seeds.begin(), seeds.end());
  }
  return plc;
}

}  // namespace sheetmesh
