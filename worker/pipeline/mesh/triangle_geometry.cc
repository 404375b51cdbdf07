#include "worker/pipeline/mesh/triangle_geometry.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sheetmesh {

std::pair<double, double> AngleRangeDegrees(const Triangle& t) {
  double lo = 180.0, hi = 0.0;
  for (int i = 0; i < 3; ++i) {
    const Vec3 u = t[(i + 1) % 3] - t[i], v = t[(i + 2) % 3] - t[i];
    const double a = Norm(u) > 0 && Norm(v) > 0 ? AngleDegrees(u, v) : 0.0;
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  return {lo, hi};
}

double AngleDegrees(const Vec3& a, const Vec3& b) {
  const double na = Norm(a), nb = Norm(b);
  if (na == 0 || nb == 0) return 180.0;
  return std::acos(std::clamp(Dot(a, b) / (na * nb), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

double DihedralAngleDegrees(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const Vec3 e = q - p;
  const double e2 = Norm2(e);
  if (e2 == 0) return 180.0;
  // Components of r - p and s - p perpendicular to the edge.
  Vec3 a = r - p, b = s - p;
  a -= e * (Dot(a, e) / e2);
  b -= e * (Dot(b, e) / e2);
  const double na = Norm(a), nb = Norm(b);
  if (na == 0 || nb == 0) return 180.0;
  const double c = std::clamp(Dot(a, b) / (na * nb), -1.0, 1.0);
  return std::acos(c) * 180.0 / std::numbers::pi;
}

Vec3 ClosestPointOnTriangle(const Vec3& p, const Triangle& t) {
  // Voronoi-region method (Ericson, Real-Time Collision Detection, 5.1.5), written out.
  const Vec3 &a = t[0], &b = t[1], &c = t[2];
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return a + ab * v;
  }
  const Vec3 cp = p - c;
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return a + ac * w;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return b + (c - b) * w;
  }
  const double denom = va + vb + vc;
  if (denom == 0) {
    const double da = Norm2(p - a), db = Norm2(p - b), dc = Norm2(p - c);
    return da <= db && da <= dc ? a : (db <= dc ? b : c);
  }
  const double v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

Vec3 ClosestOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double len2 = Norm2(d);
  const double t = len2 > 0 ? std::clamp(Dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
  return a + d * t;
}

double PointTriangleDistance2(const Vec3& p, const Triangle& t) {
  return Norm2(p - ClosestPointOnTriangle(p, t));
}

bool InsideClosedSurface(const Vec3& p, const std::vector<Vec3>& vertices,
                         const std::vector<Face>& faces) {
  // Offsets keep the ray off edges and vertices lying on round coordinates.
  const double py = p.y + 1.2345e-7 * (1 + std::abs(p.y));
  const double pz = p.z + 2.3456e-7 * (1 + std::abs(p.z));
  bool inside = false;
  for (const Face& f : faces) {
    const Vec3 &a = vertices[f[0]], &b = vertices[f[1]], &c = vertices[f[2]];
    if (std::max({a.x, b.x, c.x}) < p.x) continue;
    const Vec3 t[3] = {a, b, c};
    double e[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3& u = t[k];
      const Vec3& v = t[(k + 1) % 3];
      e[k] = (v.y - u.y) * (pz - u.z) - (v.z - u.z) * (py - u.y);
    }
    if (!((e[0] > 0 && e[1] > 0 && e[2] > 0) || (e[0] < 0 && e[1] < 0 && e[2] < 0))) continue;
    const double x = (e[1] * a.x + e[2] * b.x + e[0] * c.x) / (e[0] + e[1] + e[2]);
    if (x > p.x) inside = !inside;
  }
  return inside;
}

bool ProjectBarycentric(const Vec3& p, const Triangle& t, double* u, double* v, double* w) {
  const Vec3 v0 = t[1] - t[0], v1 = t[2] - t[0], v2 = p - t[0];
  const double d00 = Dot(v0, v0), d01 = Dot(v0, v1), d11 = Dot(v1, v1);
  const double d20 = Dot(v2, v0), d21 = Dot(v2, v1);
  const double denom = d00 * d11 - d01 * d01;
  if (!(std::abs(denom) > 1e-18 * (d00 * d11 + 1e-300))) return false;
  *v = (d11 * d20 - d01 * d21) / denom;
  *w = (d00 * d21 - d01 * d20) / denom;
  *u = 1.0 - *v - *w;
  return true;
}

namespace {

// True when `axis` separates the triangles: their projections are more than `tolerance`
// apart.
bool Separates(const Vec3& axis, const Triangle& a, const Triangle& b, double tolerance) {
  const double len = Norm(axis);
  if (len < 1e-12) return false;
  double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
  for (const Vec3& p : a) {
    const double d = Dot(p, axis) / len;
    amin = std::min(amin, d);
    amax = std::max(amax, d);
  }
  for (const Vec3& p : b) {
    const double d = Dot(p, axis) / len;
    bmin = std::min(bmin, d);
    bmax = std::max(bmax, d);
  }
  return amax < bmin - tolerance || bmax < amin - tolerance;
}

}  // namespace

bool TrianglesIntersect(const Triangle& a, const Triangle& b, double tolerance) {
  const Vec3 na = AreaVector(a), nb = AreaVector(b);
  if (Separates(na, a, b, tolerance) || Separates(nb, a, b, tolerance)) return false;
  const Vec3 ea[3] = {a[1] - a[0], a[2] - a[1], a[0] - a[2]};
  const Vec3 eb[3] = {b[1] - b[0], b[2] - b[1], b[0] - b[2]};
  for (const Vec3& u : ea) {
    for (const Vec3& v : eb) {
      if (Separates(Cross(u, v), a, b, tolerance)) return false;
    }
  }
  // Coplanar (or nearly) pairs: the edge normals within each plane.
  for (const Vec3& u : ea) {
    if (Separates(Cross(na, u), a, b, tolerance)) return false;
  }
  for (const Vec3& v : eb) {
    if (Separates(Cross(nb, v), a, b, tolerance)) return false;
  }
  return true;
}

Triangle Shrink(const Triangle& t, double fraction) {
  const Vec3 c = (t[0] + t[1] + t[2]) / 3.0;
  return {t[0] + (c - t[0]) * fraction, t[1] + (c - t[1]) * fraction, t[2] + (c - t[2]) * fraction};
}

double MeanEdgeLength(const TriangleMesh& mesh) {
  if (mesh.faces.empty()) return 0.0;
  double sum = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto c = Corners(mesh, f);
    sum += Norm(c[1] - c[0]) + Norm(c[2] - c[1]) + Norm(c[0] - c[2]);
  }
  return sum / (3.0 * mesh.faces.size());
}

double SurfaceArea(const TriangleMesh& mesh) {
  double a = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) a += Area(Corners(mesh, f));
  return a;
}

}  // namespace sheetmesh
