// A piece's chart for the mid-surface (mid_surface.h): its columns along its dominant axis on
// a grid, their walls, and the mesh of their corners. Its junctions (mid_surface_junctions.h)
// cut it at a junction line, fill it up to the line, and share the line's vertices with the
// charts that meet there. Internal to the mid-surface.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_CHART_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_CHART_H_

#include <cstdint>
#include <functional>
#include <tuple>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/surface/mid_surface_junction_line.h"

namespace sheetmesh {

// A column's kept run: the voxel centres it spans along the axis, and its two walls, each
// somewhere within the voxel beyond its last centre.
struct ChartColumn {
  bool present = false;
  bool filled = false;     // added up to a junction line: its walls the sheet's plane's there
  bool cut_away = false;   // (not present) beyond a junction line: no fill takes it again
  int32_t lo = 0, hi = 0;  // first and last voxel centre of the run
  double wall_lo = 0, wall_hi = 0;
  double mid() const { return 0.5 * (wall_lo + wall_hi); }
  double length() const { return wall_hi - wall_lo; }
};

// One piece's chart: the axis its height field runs along and its plane's fit.
// A voxel in a chart's frame: (i, j) across the axis, h along it.
struct ChartVoxel {
  int32_t i, j, h;
  bool operator<(const ChartVoxel& o) const { return std::tie(i, j, h) < std::tie(o.i, o.j, o.h); }
};

// A cut leaves the columns whose centres lie within kZipGap of its line (grid units), so the
// corners of the rim facing it keep clear of the line; the rim's columns within kZipReach are
// zipped to it.
inline constexpr double kZipGap = 1.0;
inline constexpr double kZipReach = kZipGap + 1.5;
// The farthest a zipped rim vertex lies from its line (voxels): the rim's columns within
// kZipReach of the trace, tilted up to 60 degrees, and their corners' half diagonal.
inline constexpr double kZipSpan = 2 * kZipReach + 1.0;

struct MidSurfaceChart {
  int32_t piece = 0;
  int axis = 2;                 // 0, 1, 2: x, y, z
  Vec3 normal;                  // of the least-squares plane of its voxels (unit)
  Vec3 centroid;                // of its voxels
  uint64_t voxels = 0;          // of the piece
  uint64_t columns = 0;         // columns with voxels
  uint64_t uncovered = 0;       // voxels in second runs of a column (a fold, a touching speck)
  double max_tilt_degrees = 0;  // the steepest local tilt from the axis, at a vertex
};

// A junction's trace in one chart: the line in the chart's (i, j) grid coordinates and the
// side the chart keeps (s >= 0).
struct ChartCut {
  int junction = 0;
  double ci = 0, cj = 0;  // a point of the line, grid coordinates
  double di = 0, dj = 0;  // its direction in the grid (unit)
  double ni = 0, nj = 0;  // the unit normal towards the kept side
  double Side(double i, double j) const { return (i - ci) * ni + (j - cj) * nj; }
};

class Chart {
 public:
  // The chart of a piece's voxels (at least 3) in a volume of `dims`, extended to the box
  // (ExtendToBox).
  Chart(std::vector<Index3> voxels, int32_t piece, const Dims& dims);

  const MidSurfaceChart& info() const { return info_; }
  int axis() const { return info_.axis; }

  // Voxel coordinates of grid position (i, j) (column centres at integers) at height h.
  Vec3 Point(double i, double j, double h) const;
  // Grid coordinates and height of a voxel-coordinate point.
  void ToGrid(const Vec3& p, double* i, double* j, double* h) const;

  const ChartColumn* At(int32_t i, int32_t j) const;
  int32_t ni() const { return ni_; }
  int32_t nj() const { return nj_; }

  // The plane of least squares through the mid-points of the columns between `inner` and
  // `outer` voxels of the segment a + t d (t in [ta, tb]) — or, when the chart is a plane
  // beyond `inner` (its mid-points there within a voxel of one), through all of them; false
  // when fewer than 6 columns are in the ring. `inner` keeps out where two sheets' runs
  // merge near their junction.
  bool LocalPlane(const Vec3& a, const Vec3& d, double ta, double tb, double inner, double outer,
                  Vec3* centroid, Vec3* normal, double* thickness) const;

  // How far along the line a + t d (in the direction of `sign`, +1 or -1) the chart's
  // columns within `radius` of it reach past t = from: the farthest such t, or `from`
  // where none lies beyond.
  double ReachAlong(const Vec3& a, const Vec3& d, double from, double radius, int sign) const;

  // Keeps the side `cut` names: columns beyond the line go, columns between the chart and
  // the line within `band` of it and along the junction's extent are filled on the plane
  // (`plane_point`, `plane_normal`) with `thickness`, and those within `band` lie on it.
  void Cut(const ChartCut& cut, const JunctionLine& line, double band, const Vec3& plane_point,
           const Vec3& plane_normal, double thickness);
  // How far from `line` (grid units, on the kept side of `cut`) the chart's nearest column
  // along the line's extent lies: the gap a fill must bridge (the band a shallow crossing's
  // merged runs took). Infinity when none is along it.
  double Gap(const ChartCut& cut, const JunctionLine& line) const;
  // The fraction of the chart's columns on each side of `cut` (s >= 0, s < 0).
  void Sides(const ChartCut& cut, uint64_t* kept, uint64_t* beyond) const;
  // The chart's columns along `line`'s extent (its strip: the line's ends there, open where
  // an end lies on the box) on each side of `cut`, and how far beyond it the farthest lies
  // (grid units; 0 when none). A line that ends inside a sheet cuts only its strip.
  struct StripSides {
    uint64_t kept = 0, beyond = 0;
    double farthest_beyond = 0;
  };
  StripSides SidesAlong(const ChartCut& cut, const JunctionLine& line) const;
  // The trace of `line` in this chart, keeping the side towards `towards` (a voxel-coordinate
  // point of the chart).
  ChartCut Trace(const JunctionLine& line, int index, const Vec3& towards) const;
  // The columns beyond `cut` as a chart of their own (they leave this one).
  std::vector<Index3> TakeBeyond(const ChartCut& cut);
  // The voxels of the kept runs, for a map of which chart holds which voxel.
  template <class F>
  void ForEachVoxel(F&& f) const {
    for (int32_t i = 0; i < ni_; ++i) {
      for (int32_t j = 0; j < nj_; ++j) {
        const ChartColumn* c = At(i, j);
        if (c == nullptr || c->filled) continue;
        for (int32_t h = c->lo; h <= c->hi; ++h) {
          const Vec3 p = Point(i, j, h);
          f(Index3{static_cast<int32_t>(std::lround(p.x)), static_cast<int32_t>(std::lround(p.y)),
                   static_cast<int32_t>(std::lround(p.z))},
            !HasAll4(i, j));
        }
      }
    }
  }

  // Where the sheet leaves the box through a face across the chart's axis, its runs end at
  // the box, not at its walls: each such column's wall at the box is put the sheet's
  // thickness nearby beyond the other, and a few rings of columns are added past the face on
  // the plane of the columns near it, so that the mesh runs past the box and its clip
  // (BuildMidSurface's clip to the box) ends the sheet on the face where its plane meets it.
  void ExtendToBox();

  // Appends the chart's vertices and faces to `mesh`; the rim facing each cut is joined to
  // its junction's samples (shared with the other charts there, made when first used) by a
  // strip of triangles.
  void Mesh(std::vector<JunctionLine>* lines, TriangleMesh* mesh);

 private:
  // Joins a chain of rim vertices (t along the line, vertex) to the line's samples over the
  // same stretch by a strip, each step taking the shorter next diagonal; an end of the line
  // on the box that the chain stops short of by less than a step and a voxel is taken too.
  void ZipToLine(std::vector<std::pair<double, uint32_t>> rim, const JunctionLine& line,
                 const std::function<uint32_t(int)>& sample,
                 const std::function<void(uint32_t, uint32_t, uint32_t)>& emit,
                 TriangleMesh* mesh) const;
  bool HasAll4(int32_t i, int32_t j) const;
  // Whether grid position (i, j) at height h lies along `line`'s extent (within half a
  // voxel of its ends; unbounded past an end on the box).
  bool AlongLine(const JunctionLine& line, double i, double j, double h) const;
  // Whether grid position (i, j) lies within the volume across the axis.
  bool InBox(int32_t i, int32_t j) const;
  // Whether p lies on a face of the box [-0.5, n - 0.5] (a junction line's end there),
  // within kOnBoxFace: lines merged from an X's halves end that near it, and the mesh's
  // clip to the box puts such a vertex on the face.
  static constexpr double kOnBoxFace = 0.1;
  bool OnBoxFace(const Vec3& p) const;
  // Grows the grid to hold grid positions lo..hi (which may be negative: the origin moves).
  void Grow(int32_t lo_i, int32_t lo_j, int32_t hi_i, int32_t hi_j);
  void Columns(std::vector<Index3> voxels);
  void SmoothWalls();
  ChartColumn& Cell(int32_t i, int32_t j) { return grid_[static_cast<size_t>(i) * nj_ + j]; }
  void Corner(int32_t i, int32_t j, double* h, double* length, double* gi, double* gj) const;

  MidSurfaceChart info_;
  Dims dims_;
  int32_t i0_ = 0, j0_ = 0, ni_ = 0, nj_ = 0;
  std::vector<ChartColumn> grid_;
  std::vector<ChartCut> cuts_;
};

// How many faces of the box [-0.5, n - 0.5] of `dims` the point p lies on, within `within`
// voxels.
int BoxFacesAt(const Vec3& p, const Dims& dims, double within);

// The least-squares plane of `points` (centroid and unit normal of least spread).
void FitPlanePoints(const std::vector<Vec3>& points, Vec3* centroid, Vec3* normal);

// The principal direction of `points` (unit, of most spread) and their centroid.
void PrincipalLine(const std::vector<Vec3>& points, Vec3* centroid, Vec3* direction);

// The part t in [*t0, *t1] of the line p + t u inside the box [-0.5, n - 0.5] on each axis;
// false when none is.
bool ClipToBox(const Vec3& p, const Vec3& u, const Dims& dims, double* t0, double* t1);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_CHART_H_
