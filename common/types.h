// Basic value types of the pipeline: volume dimensions, voxel indices and 3-vectors.
#ifndef SHEETMESH_COMMON_TYPES_H_
#define SHEETMESH_COMMON_TYPES_H_

#include <cmath>
#include <cstdint>
#include <string>

namespace sheetmesh {

// Dimensions of a voxel box, x fastest. Each extent is >= 0.
struct Dims {
  int64_t nx = 0;
  int64_t ny = 0;
  int64_t nz = 0;

  int64_t num_voxels() const { return nx * ny * nz; }
  int64_t num_rows() const { return ny * nz; }
  bool Contains(int64_t x, int64_t y, int64_t z) const {
    return x >= 0 && y >= 0 && z >= 0 && x < nx && y < ny && z < nz;
  }
  std::string ToString() const;  // "200x42x100"
  friend bool operator==(const Dims&, const Dims&) = default;
};

// A voxel index; voxel centres sit at integer coordinates.
struct Index3 {
  int32_t x = 0;
  int32_t y = 0;
  int32_t z = 0;
  friend bool operator==(const Index3&, const Index3&) = default;
};

struct Vec3 {
  double x = 0, y = 0, z = 0;

  Vec3() = default;
  constexpr Vec3(double ax, double ay, double az) : x(ax), y(ay), z(az) {}
  static Vec3 Of(const Index3& i) { return Vec3(i.x, i.y, i.z); }

  double operator[](int k) const { return k == 0 ? x : (k == 1 ? y : z); }
  double& operator[](int k) { return k == 0 ? x : (k == 1 ? y : z); }
  Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
  Vec3 operator-() const { return {-x, -y, -z}; }
  Vec3& operator+=(const Vec3& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  Vec3& operator-=(const Vec3& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  Vec3& operator*=(double s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  friend bool operator==(const Vec3&, const Vec3&) = default;
};

inline double Dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Norm2(const Vec3& a) { return Dot(a, a); }
inline double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }
// Returns a/|a|, or the zero vector when |a| is 0.
inline Vec3 Normalized(const Vec3& a) {
  const double n = Norm(a);
  return n > 0 ? a / n : Vec3();
}

// Physical placement of voxel indices: physical = index * spacing + origin.
struct Placement {
  Vec3 spacing{1, 1, 1};  // voxel size per axis, in the volume's length unit
  Vec3 origin{0, 0, 0};   // physical position of voxel (0,0,0)'s centre
  std::string unit;       // length unit if known ("mm", "um"); empty if unknown

  Vec3 ToPhysical(const Vec3& index) const {
    return {index.x * spacing.x + origin.x, index.y * spacing.y + origin.y,
            index.z * spacing.z + origin.z};
  }
};

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_TYPES_H_
