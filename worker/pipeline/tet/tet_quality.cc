#include "worker/pipeline/tet/tet_quality.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sheetmesh {

double MinDihedralDegrees(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 ab = b - a, ac = c - a, ad = d - a;
  if (Dot(Cross(ab, ac), ad) <= 0) return -1.0;
  // Outward normals of the faces opposite d, c, b and a (the tetrahedron is positive).
  Vec3 n[4] = {Cross(ac, ab), Cross(ab, ad), Cross(ad, ac), Cross(c - b, d - b)};
  for (Vec3& v : n) {
    const double len = Norm(v);
    if (!(len > 0)) return -1.0;
    v = v / len;
  }
  // The dihedral angle between faces i and j is π minus the angle between their normals;
  // the smallest angle has the largest -n_i·n_j.
  double worst = -1.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) worst = std::max(worst, -Dot(n[i], n[j]));
  return std::acos(std::clamp(worst, -1.0, 1.0)) * (180.0 / std::numbers::pi);
}

TetShape MeasureTet(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  TetShape s;
  const Vec3 p[4] = {a, b, c, d};
  const double v = std::abs(TetVolume(a, b, c, d));
  // Edges.
  double l2sum = 0, lmin = 1e300, lmax = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      const double l2 = Norm2(p[i] - p[j]);
      l2sum += l2;
      lmin = std::min(lmin, std::sqrt(l2));
      lmax = std::max(lmax, std::sqrt(l2));
    }
  s.gamma = l2sum > 0 ? 72.0 * std::sqrt(3.0) * v / std::pow(l2sum, 1.5) : 0;
  s.edge_aspect = lmax > 0 ? lmin / lmax : 0;
  // Face areas and normals (outward by construction of the opposite vertex).
  const int face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  Vec3 n[4];
  double area = 0;
  for (int f = 0; f < 4; ++f) {
    const Vec3 an = Cross(p[face[f][1]] - p[face[f][0]], p[face[f][2]] - p[face[f][0]]);
    area += 0.5 * Norm(an);
    // Point the normal away from the opposite vertex.
    n[f] = Dot(an, p[f] - p[face[f][0]]) > 0 ? -an : an;
    n[f] = Normalized(n[f]);
  }
  // Dihedral angle at the edge shared by faces f and g: π minus the angle between their
  // outward normals.
  double dmin = 180;
  for (int f = 0; f < 4; ++f)
    for (int g = f + 1; g < 4; ++g) {
      const double cosang = std::clamp(-Dot(n[f], n[g]), -1.0, 1.0);
      dmin = std::min(dmin, std::acos(cosang) * 180.0 / std::numbers::pi);
    }
  s.min_dihedral_degrees = v > 0 ? dmin : 0;
  s.radius_aspect = RadiusAspect(v, area, a, b, c, d);
  return s;
}

double RadiusAspect(double volume, double area, const Vec3& a, const Vec3& b, const Vec3& c,
                    const Vec3& d) {
  // Inradius 3V / A; circumradius from the circumcentre.
  const double r_in = area > 0 ? 3 * volume / area : 0;
  Vec3 cc;
  const double r_circ = Circumcentre(a, b, c, d, &cc) ? Norm(cc - a) : 0;
  return r_circ > 0 ? 3 * r_in / r_circ : 0;
}

double RadiusAspect(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double v = std::abs(TetVolume(a, b, c, d));
  const double area = 0.5 * (Norm(Cross(c - b, d - b)) + Norm(Cross(d - a, c - a)) +
                             Norm(Cross(b - a, d - a)) + Norm(Cross(c - a, b - a)));
  return RadiusAspect(v, area, a, b, c, d);
}

namespace {

QualityStat Stat(const std::string& name, double lo, double hi, int bins) {
  QualityStat s;
  s.name = name;
  s.lo = lo;
  s.hi = hi;
  s.min = 1e300;
  s.histogram.assign(bins, 0);
  return s;
}

void Add(QualityStat* s, double v) {
  s->min = std::min(s->min, v);
  s->mean += v;
  const int bins = static_cast<int>(s->histogram.size());
  const int b = std::clamp(static_cast<int>((v - s->lo) / (s->hi - s->lo) * bins), 0, bins - 1);
  ++s->histogram[b];
}

}  // namespace

TetQuality MeasureQuality(const TetMesh& mesh) {
  TetQuality q;
  q.min_dihedral = Stat("min_dihedral_degrees", 0, 90, 18);
  q.gamma = Stat("gamma", 0, 1, 20);
  q.edge_aspect = Stat("edge_aspect", 0, 1, 20);
  q.radius_aspect = Stat("radius_aspect", 0, 1, 20);
  q.tets = mesh.tets.size();
  q.nodes = mesh.nodes.size();
  for (const Tet& t : mesh.tets) {
    const Vec3 &a = mesh.nodes[t[0]], &b = mesh.nodes[t[1]], &c = mesh.nodes[t[2]],
               &d = mesh.nodes[t[3]];
    const double v = TetVolume(a, b, c, d);
    q.volume += std::abs(v);
    q.inverted += v <= 0;
    const TetShape s = MeasureTet(a, b, c, d);
    Add(&q.min_dihedral, s.min_dihedral_degrees);
    Add(&q.gamma, s.gamma);
    Add(&q.edge_aspect, s.edge_aspect);
    Add(&q.radius_aspect, s.radius_aspect);
  }
  for (QualityStat* s : {&q.min_dihedral, &q.gamma, &q.edge_aspect, &q.radius_aspect}) {
    if (q.tets > 0) {
      s->mean /= q.tets;
    } else {
      s->min = 0;
    }
  }
  return q;
}

}  // namespace sheetmesh
