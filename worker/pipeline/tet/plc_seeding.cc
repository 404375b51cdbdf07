#include <algorithm>
#include <cmath>
#include <limits>

#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

// Seed points for TetGen: a body-centred cubic (BCC) lattice, whose Delaunay
// tetrahedra all have dihedral angles of 60° and 90° and a radius aspect of 0.95, far
// better than the Delaunay refinement makes on its own. Level 0 has the given spacing
// and fills the space between kLatticeKeep spacings and 1 / grading further spacings
// from the sheets; each further level doubles the spacing and the band, so the mesh
// grades away from the sheets; the last level fills the rest. Points keep kLatticeKeep
// spacings of their level off the box faces. Near the sheets TetGen places the points,
// as the sheet triangles and their refinement decide.
//
// Each change of level leaves a layer of worse tetrahedra where the two spacings meet,
// and so does each box face, where the face's points meet the lattice's rows. A level
// whose spacing is over half the box's thinnest side is not used (its finer neighbour
// fills the rest): between the margins on both sides it would have room for a row or two
// only. Earlier a quarter: NETL's box is 42 voxels thick, and at a quarter its lattice had
// one level, 36 tetrahedra per sheet triangle at r = 5; at half, 15 with the same smallest
// angle (bench/RESULTS.md, issue 65). Otherwise the levels go on to the box's scale.
constexpr double kLatticeKeep = 0.6;
constexpr int kLatticeMaxLevels = 20;
constexpr double kLatticeFit = 2;  // a level's spacing fits this many times in the box

// Walks the seeding's levels, finest first: calls candidates(h, in_band) with level l's
// spacing h, where in_band(p) tells whether p's distance to the sheets lies in that
// level's band.
template <class Candidates>
void ForEachLevel(const Plc& plc, const LatticeLevels& levels, Candidates&& candidates) {
  std::vector<Triangle> tris;
  std::vector<Vec3> box_lo, box_hi;
  for (const Face& f : plc.sheet_triangles) {
    tris.push_back({plc.vertices[f[0]], plc.vertices[f[1]], plc.vertices[f[2]]});
    TriangleBox(tris.back(), 0.0, &box_lo.emplace_back(), &box_hi.emplace_back());
  }
  const size_t n = levels.spacing.size();
  for (size_t level = 0; level < n; ++level) {
    const double inner = levels.inner[level];
    const bool last = level + 1 == n;
    const double outer = levels.outer[level];  // not for the last
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
        too_close = near2 < inner * inner;
      });
      if (too_close) return false;           // a finer level's, or TetGen's
      return last || near2 < outer * outer;  // else a coarser level's
    };
    candidates(levels.spacing[level], in_band);
  }
}

// A sheet lying nearer a box face than the lattice's first band (kLatticeKeep spacings)
// keeps the face's seeded points away, so TetGen, which may add none there (-Y), spans the
// face beneath it with a few triangles as long as the face (a grazing sheet at r = 11: a
// box triangle 120 voxels long 5 voxels under the sheet, tetrahedra of 4.5° between). Each
// sheet vertex within `reach` of a face, where its sheet lies within kBeneathDegrees of the
// face's plane, gives the face a point straight beneath it: the layer between the sheet and
// the face is then prisms of the sheet's triangles. Such points keep kBeneathApart of the
// first spacing from each other and from the face's other points, and from the sheets'
// traces on the face and the face's edges.
constexpr double kBeneathDegrees = 45;
constexpr double kBeneathApart = 0.5;

void AddPointsBeneathSheets(const Plc& plc, double reach, std::vector<BoxPoint>* points) {
  const double apart = kBeneathApart * reach / kLatticeKeep;
  const double cos_max = std::cos(kBeneathDegrees * M_PI / 180.0);
  const Vec3 lo = plc.box_lo, hi = plc.box_hi;
  const double tol = 1e-9 * (1.0 + Norm(hi - lo));
  std::vector<Vec3> normal(plc.vertices.size(), Vec3(0, 0, 0));
  std::vector<uint8_t> used(plc.vertices.size(), 0);
  for (const Face& f : plc.sheet_triangles) {
    const Vec3 n =
        Cross(plc.vertices[f[1]] - plc.vertices[f[0]], plc.vertices[f[2]] - plc.vertices[f[0]]);
    for (uint32_t v : f) {
      // One side's normal: a sheet's faces may be wound either way, so flip to agree.
      normal[v] = normal[v] + (Dot(normal[v], n) < 0 ? n * -1.0 : n);
      used[v] = 1;
    }
  }
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    for (int high = 0; high < 2; ++high) {
      const double plane = high ? hi[k] : lo[k];
      const uint8_t bit = static_cast<uint8_t>(1 << (2 * k + high));
      // What a new point keeps away from: the face's points and the sheets' traces on it.
      SpatialGrid near(apart);
      std::vector<Vec3> taken;
      auto keep = [&](const Vec3& p) {
        near.Insert(static_cast<uint32_t>(taken.size()), p, p);
        taken.push_back(p);
      };
      for (const BoxPoint& q : *points) {
        if (q.on_face & bit) keep(q.p);
      }
      for (uint32_t v = 0; v < plc.vertices.size(); ++v) {
        if (used[v] && std::abs(plc.vertices[v][k] - plane) < tol) keep(plc.vertices[v]);
      }
      std::vector<std::pair<Vec3, Vec3>> traces;
      for (const Face& f : plc.sheet_triangles) {
        for (int e = 0; e < 3; ++e) {
          const Vec3 &p = plc.vertices[f[e]], &q = plc.vertices[f[(e + 1) % 3]];
          if (std::abs(p[k] - plane) < tol && std::abs(q[k] - plane) < tol) {
            traces.push_back({p, q});
          }
        }
      }
      SpatialGrid trace_grid(apart);
      for (uint32_t i = 0; i < traces.size(); ++i) {
        const auto& [p, q] = traces[i];
        trace_grid.Insert(i, Vec3(std::min(p.x, q.x), std::min(p.y, q.y), std::min(p.z, q.z)),
                          Vec3(std::max(p.x, q.x), std::max(p.y, q.y), std::max(p.z, q.z)));
      }
      for (uint32_t v = 0; v < plc.vertices.size(); ++v) {
        const Vec3& x = plc.vertices[v];
        const double d = std::abs(x[k] - plane);
        if (!used[v] || d < tol || d >= reach || Norm(normal[v]) == 0) continue;
        if (std::abs(normal[v][k]) < cos_max * Norm(normal[v])) continue;
        Vec3 p = x;
        p[k] = plane;
        if (p[a] < lo[a] + apart || p[a] > hi[a] - apart || p[b] < lo[b] + apart ||
            p[b] > hi[b] - apart) {
          continue;
        }
        const Vec3 r(apart, apart, apart);
        bool crowded = false;
        near.Query(p - r, p + r,
                   [&](uint32_t i) { crowded = crowded || Norm2(taken[i] - p) < apart * apart; });
        trace_grid.Query(p - r, p + r, [&](uint32_t i) {
          crowded = crowded || Norm2(p - ClosestOnSegment(p, traces[i].first, traces[i].second)) <
                                   apart * apart;
        });
        if (crowded) continue;
        keep(p);
        points->push_back({p, bit});
      }
    }
  }
}

}  // namespace

LatticeLevels GradeLattice(const Vec3& box_lo, const Vec3& box_hi, double spacing, double grading) {
  LatticeLevels levels;
  if (!(spacing > 0) || !(grading > 0)) return levels;
  const Vec3 extent = box_hi - box_lo;
  const double thinnest = std::min({std::abs(extent.x), std::abs(extent.y), std::abs(extent.z)});
  int n = 1;
  while (n < kLatticeMaxLevels && kLatticeFit * spacing * std::ldexp(1.0, n) <= thinnest) ++n;
  double inner = kLatticeKeep * spacing;  // where level 0 starts
  for (int level = 0; level < n; ++level) {
    const double h = spacing * std::ldexp(1.0, level);
    const double outer = inner + h / grading;
    levels.spacing.push_back(h);
    levels.inner.push_back(inner);
    levels.outer.push_back(outer);
    inner = outer;
  }
  return levels;
}

double LatticeLevels::SpacingAt(double d) const {
  if (spacing.empty() || d < inner[0]) return 0;
  for (size_t l = 0; l + 1 < spacing.size(); ++l) {
    if (d < outer[l]) return spacing[l];
  }
  return spacing.back();
}

std::vector<Vec3> SeedLattice(const Plc& plc, const LatticeLevels& levels) {
  std::vector<Vec3> seeds;
  const Vec3 lo = plc.box_lo, hi = plc.box_hi;
  ForEachLevel(plc, levels, [&](double h, const auto& in_band) {
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

// Points on the box's edges and faces for a TetGen that may add none there (-Y), graded
// like the lattice: on each edge, points every h of their level; on each face, rows h
// apart with every other row shifted by h/2 (triangles of angles near 63°, 63° and 53°),
// kept kLatticeKeep · h off the face's edges. Sheet traces keep their band free, as for
// the lattice.
std::vector<BoxPoint> SeedBox(const Plc& plc, const LatticeLevels& levels) {
  std::vector<BoxPoint> points;
  const Vec3 lo = plc.box_lo, hi = plc.box_hi;
  ForEachLevel(plc, levels, [&](double h, const auto& in_band) {
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
  if (!levels.spacing.empty()) AddPointsBeneathSheets(plc, levels.inner[0], &points);
  return points;
}

}  // namespace sheetmesh
