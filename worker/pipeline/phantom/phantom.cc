#include "worker/pipeline/phantom/phantom.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <thread>

#include "absl/strings/str_cat.h"
#include "common/json_text.h"
#include "common/orientation.h"
#include "common/random.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kWaves = 4;

// A smooth random field in [-1, 1]: a sum of plane waves in the sheet's (u, v) plane.
struct Waves {
  double kx[kWaves], ky[kWaves], phase[kWaves];
  double Eval(double a, double b) const {
    double s = 0;
    for (int k = 0; k < kWaves; ++k) s += std::sin(kx[k] * a + ky[k] * b + phase[k]);
    return s / kWaves;
  }
};

Waves RandomWaves(Rng& rng, double min_wavelength, double max_wavelength) {
  Waves w;
  for (int k = 0; k < kWaves; ++k) {
    const double lambda = rng.Uniform(min_wavelength, max_wavelength);
    const double dir = rng.Uniform(0, 2 * kPi);
    w.kx[k] = 2 * kPi / lambda * std::cos(dir);
    w.ky[k] = 2 * kPi / lambda * std::sin(dir);
    w.phase[k] = rng.Uniform(0, 2 * kPi);
  }
  return w;
}

// The sheet's fields tabulated on a 2-voxel grid over its outline and read bilinearly, so
// that the per-voxel cost stays a few loads whatever the number of waves.
struct SheetFields {
  static constexpr double kStep = 2.0;
  double a0 = 0, b0 = 0;
  int na = 0, nb = 0;
  // Per grid node: mid-surface offset, half aperture, top and bottom wall offsets.
  std::vector<std::array<float, 4>> node;

  std::array<float, 4> At(double a, double b) const {
    double fa = std::clamp((a - a0) / kStep, 0.0, na - 1.001);
    double fb = std::clamp((b - b0) / kStep, 0.0, nb - 1.001);
    const int ia = static_cast<int>(fa), ib = static_cast<int>(fb);
    fa -= ia;
    fb -= ib;
    const auto& p00 = node[ib * na + ia];
    const auto& p10 = node[ib * na + ia + 1];
    const auto& p01 = node[(ib + 1) * na + ia];
    const auto& p11 = node[(ib + 1) * na + ia + 1];
    std::array<float, 4> out;
    for (int k = 0; k < 4; ++k) {
      out[k] = static_cast<float>((1 - fb) * ((1 - fa) * p00[k] + fa * p10[k]) +
                                  fb * ((1 - fa) * p01[k] + fa * p11[k]));
    }
    return out;
  }
};

struct PlannedSheet {
  PhantomSheet* sheet;
  SheetFields fields;
  double bound;  // |w| beyond this is never inside
};

SheetFields Tabulate(const PhantomSheet& s, const Waves& und, const Waves& ap, const Waves& top,
                     const Waves& bot, double variation, double* ap_min, double* ap_max) {
  SheetFields f;
  f.a0 = -s.half_extent_u - 2 * SheetFields::kStep;
  f.b0 = -s.half_extent_v - 2 * SheetFields::kStep;
  f.na = static_cast<int>(
             std::ceil(2 * (s.half_extent_u + 4 * SheetFields::kStep) / SheetFields::kStep)) +
         2;
  f.nb = static_cast<int>(
             std::ceil(2 * (s.half_extent_v + 4 * SheetFields::kStep) / SheetFields::kStep)) +
         2;
  f.node.resize(static_cast<size_t>(f.na) * f.nb);
  *ap_min = 1e300;
  *ap_max = 0;
  for (int j = 0; j < f.nb; ++j) {
    for (int i = 0; i < f.na; ++i) {
      const double a = f.a0 + i * SheetFields::kStep, b = f.b0 + j * SheetFields::kStep;
      const double aperture = std::max(1.0, s.aperture_mean * (1 + variation * ap.Eval(a, b)));
      if ((a * a) / (s.half_extent_u * s.half_extent_u) +
              (b * b) / (s.half_extent_v * s.half_extent_v) <=
          1.0) {
        *ap_min = std::min(*ap_min, aperture);
        *ap_max = std::max(*ap_max, aperture);
      }
      f.node[j * f.na + i] = {static_cast<float>(s.undulation * und.Eval(a, b)),
                              static_cast<float>(aperture / 2),
                              static_cast<float>(s.wall_roughness * top.Eval(a, b)),
                              static_cast<float>(s.wall_roughness * bot.Eval(a, b))};
    }
  }
  if (*ap_max == 0) *ap_min = *ap_max = s.aperture_mean;
  return f;
}

bool InsideOutline(const PhantomSheet& s, double a, double b) {
  if ((a * a) / (s.half_extent_u * s.half_extent_u) +
          (b * b) / (s.half_extent_v * s.half_extent_v) >
      1.0) {
    return false;
  }
  for (const PhantomHole& h : s.holes) {
    if ((a - h.u) * (a - h.u) + (b - h.v) * (b - h.v) < h.radius * h.radius) return false;
  }
  for (const PhantomGap& g : s.gaps) {
    if (std::abs(a * std::cos(g.angle) + b * std::sin(g.angle) - g.offset) < g.width / 2) {
      return false;
    }
  }
  return !s.has_cut || a * s.cut_u + b * s.cut_v >= 0;
}

absl::Status Validate(const PhantomOptions& o) {
  if (o.dims.nx <= 0 || o.dims.ny <= 0 || o.dims.nz <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("phantom dims ", o.dims.ToString(), " must all be positive"));
  }
  if (!(o.aperture_voxels > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("phantom aperture_voxels ", o.aperture_voxels, " must be positive"));
  }
  if (o.num_sheets < 0 || o.holes_per_sheet < 0 || o.fragmented_sheets < 0 || o.num_specks < -1 ||
      o.vugs_per_sheet < 0) {
    return absl::InvalidArgumentError("phantom counts must not be negative");
  }
  if (o.vugs_per_sheet > 0 && !(o.vug_radius_voxels > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("phantom vug_radius_voxels ", o.vug_radius_voxels, " must be positive"));
  }
  if (!(o.extent_fraction > 0 && o.extent_fraction <= 1.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("phantom extent_fraction ", o.extent_fraction, " must be in (0, 1.5]"));
  }
  if (!(o.junction_degrees >= 0 && o.junction_degrees <= 90)) {
    return absl::InvalidArgumentError(absl::StrCat("phantom junction_degrees ", o.junction_degrees,
                                                   " must be in [0, 90] (0: none)"));
  }
  if (!(o.min_dip_degrees >= 0 && o.min_dip_degrees <= o.max_dip_degrees &&
        o.max_dip_degrees <= 90)) {
    return absl::InvalidArgumentError(
        absl::StrCat("phantom dips ", o.min_dip_degrees, " to ", o.max_dip_degrees,
                     " degrees must satisfy 0 <= min_dip_degrees <= max_dip_degrees <= 90"));
  }
  return absl::OkStatus();
}

// Geometry decided by PlanPhantom, kept with the tables needed to voxelize it.
struct Plan {
  std::vector<PlannedSheet> sheets;
};

Plan MakePlan(PhantomTruth* truth) {
  const PhantomOptions& o = truth->options;
  Rng rng(o.seed * 0x9E3779B97F4A7C15ULL + 12345);
  Plan plan;
  for (PhantomSheet& s : truth->sheets) {
    const Waves und = RandomWaves(rng, 0.6 * s.half_extent_u, 1.6 * s.half_extent_u);
    const Waves ap = RandomWaves(rng, 20, 60);
    const Waves top = RandomWaves(rng, 3, 9);
    const Waves bot = RandomWaves(rng, 3, 9);
    PlannedSheet p;
    p.sheet = &s;
    p.fields =
        Tabulate(s, und, ap, top, bot, o.aperture_variation, &s.aperture_min, &s.aperture_max);
    p.bound = s.undulation + s.aperture_max / 2 + s.wall_roughness + 1.0;
    plan.sheets.push_back(std::move(p));
  }
  return plan;
}

template <class T>
void FillSlab(const PhantomTruth& truth, const Plan& plan, int64_t z_begin, int64_t z_end,
              int64_t slab_z0, T* slab, std::vector<uint64_t>* sheet_counts) {
  const PhantomOptions& o = truth.options;
  const Dims& d = o.dims;
  const T value = static_cast<T>(o.sheet_value);
  for (int64_t z = z_begin; z < z_end; ++z) {
    for (int64_t y = 0; y < d.ny; ++y) {
      T* row = slab + ((z - slab_z0) * d.ny + y) * d.nx;
      for (size_t k = 0; k < plan.sheets.size(); ++k) {
        const PlannedSheet& ps = plan.sheets[k];
        const PhantomSheet& s = *ps.sheet;
        const Vec3 d0 = Vec3(0, y, z) - s.center;
        const double w0 = Dot(d0, s.normal);
        int64_t x0 = 0, x1 = d.nx;  // candidate x range [x0, x1)
        if (std::abs(s.normal.x) > 1e-9) {
          double lo = (-ps.bound - w0) / s.normal.x, hi = (ps.bound - w0) / s.normal.x;
          if (lo > hi) std::swap(lo, hi);
          x0 = std::max<int64_t>(0, static_cast<int64_t>(std::floor(lo)));
          x1 = std::min<int64_t>(d.nx, static_cast<int64_t>(std::ceil(hi)) + 1);
        } else if (std::abs(w0) > ps.bound) {
          continue;
        }
        const double a0 = Dot(d0, s.u), b0 = Dot(d0, s.v);
        for (int64_t x = x0; x < x1; ++x) {
          const double w = w0 + x * s.normal.x;
          const double a = a0 + x * s.u.x, b = b0 + x * s.v.x;
          if (!InsideOutline(s, a, b)) continue;
          const std::array<float, 4> f = ps.fields.At(a, b);
          if (w < f[0] - f[1] - f[3] || w > f[0] + f[1] + f[2]) continue;
          row[x] = value;
          ++(*sheet_counts)[k];
        }
      }
    }
  }
  // Vugs open the sheets into lenses.
  for (const PhantomVug& vug : truth.vugs) {
    const double r = std::max(vug.radius_along, vug.radius_across);
    const int64_t z0 = std::max<int64_t>(z_begin, std::floor(vug.center.z - r));
    const int64_t z1 = std::min<int64_t>(z_end, std::ceil(vug.center.z + r) + 1);
    for (int64_t z = z0; z < z1; ++z) {
      for (int64_t y = std::max<int64_t>(0, std::floor(vug.center.y - r));
           y <= std::min<int64_t>(d.ny - 1, std::ceil(vug.center.y + r)); ++y) {
        T* row = slab + ((z - slab_z0) * d.ny + y) * d.nx;
        for (int64_t x = std::max<int64_t>(0, std::floor(vug.center.x - r));
             x <= std::min<int64_t>(d.nx - 1, std::ceil(vug.center.x + r)); ++x) {
          if (row[x] != value && vug.Contains(Vec3(x, y, z))) {
            row[x] = value;
            ++(*sheet_counts)[vug.sheet];
          }
        }
      }
    }
  }
  // Specks last: they may touch sheets, as minor objects do in real rock.
  const T speck = static_cast<T>(o.speck_value);
  for (const PhantomSpeck& sp : truth.specks) {
    const int64_t r = static_cast<int64_t>(std::ceil(sp.radius));
    const int64_t cz = std::llround(sp.center.z);
    for (int64_t z = std::max(z_begin, cz - r); z < std::min(z_end, cz + r + 1); ++z) {
      for (int64_t y = std::max<int64_t>(0, std::llround(sp.center.y) - r);
           y <= std::min<int64_t>(d.ny - 1, std::llround(sp.center.y) + r); ++y) {
        for (int64_t x = std::max<int64_t>(0, std::llround(sp.center.x) - r);
             x <= std::min<int64_t>(d.nx - 1, std::llround(sp.center.x) + r); ++x) {
          if (Norm2(Vec3(x, y, z) - sp.center) <= sp.radius * sp.radius) {
            slab[((z - slab_z0) * d.ny + y) * d.nx + x] = speck;
          }
        }
      }
    }
  }
}

template <class T>
absl::Status Generate(PhantomTruth* truth, VolumeSink& sink, const Progress& progress) {
  const PhantomOptions& o = truth->options;
  const Dims& d = o.dims;
  const Plan plan = MakePlan(truth);
  const int64_t slice = d.nx * d.ny;
  const int64_t slab = std::clamp<int64_t>((int64_t{32} << 20) / (slice * sizeof(T)), 1, d.nz);
  std::vector<T> buffer(static_cast<size_t>(slab * slice));
  std::vector<uint64_t> counts(plan.sheets.size(), 0);
  const T background = static_cast<T>(o.background_value);
  const T sheet_value = static_cast<T>(o.sheet_value);
  const T speck_value = static_cast<T>(o.speck_value);
  truth->sheet_voxels = 0;
  const unsigned threads = std::max(1u, std::min(4u, std::thread::hardware_concurrency()));
  for (int64_t z0 = 0; z0 < d.nz; z0 += slab) {
    const int64_t n = std::min(slab, d.nz - z0);
    std::fill(buffer.begin(), buffer.begin() + n * slice, background);
    // Split the slab's slices between threads; each keeps its own counts.
    std::vector<std::vector<uint64_t>> part(threads, std::vector<uint64_t>(counts.size(), 0));
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) {
      const int64_t zb = z0 + n * t / threads, ze = z0 + n * (t + 1) / threads;
      pool.emplace_back(
          [&, t, zb, ze] { FillSlab<T>(*truth, plan, zb, ze, z0, buffer.data(), &part[t]); });
    }
    for (std::thread& th : pool) th.join();
    for (const auto& p : part) {
      for (size_t k = 0; k < counts.size(); ++k) counts[k] += p[k];
    }
    for (int64_t i = 0; i < n * slice; ++i) {
      truth->sheet_voxels +=
          (buffer[i] == sheet_value || buffer[i] == speck_value) && buffer[i] != background;
    }
    SM_RETURN_IF_ERROR(sink.WriteSlices(
        n, std::span<const std::byte>(reinterpret_cast<const std::byte*>(buffer.data()),
                                      static_cast<size_t>(n * slice * sizeof(T)))));
    SM_RETURN_IF_ERROR(progress.Update(double(z0 + n) / d.nz));
  }
  for (size_t k = 0; k < counts.size(); ++k) truth->sheets[k].voxels = counts[k];
  // Specks' own voxels, for the truth file (overlaps with sheets included).
  truth->speck_voxels = 0;
  for (const PhantomSpeck& sp : truth->specks) {
    const int64_t r = static_cast<int64_t>(std::ceil(sp.radius));
    for (int64_t dz = -r; dz <= r; ++dz) {
      for (int64_t dy = -r; dy <= r; ++dy) {
        for (int64_t dx = -r; dx <= r; ++dx) {
          const Vec3 p(std::llround(sp.center.x) + dx, std::llround(sp.center.y) + dy,
                       std::llround(sp.center.z) + dz);
          if (d.Contains(static_cast<int64_t>(p.x), static_cast<int64_t>(p.y),
                         static_cast<int64_t>(p.z)) &&
              Norm2(p - sp.center) <= sp.radius * sp.radius) {
            ++truth->speck_voxels;
          }
        }
      }
    }
  }
  return sink.Finish();
}

// Collects slices in memory.
class DenseSink : public VolumeSink {
 public:
  explicit DenseSink(DenseVolume* out) : out_(out) {
    info_ = out->info;
    info_.path = "<phantom>";
  }
  absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) override {
    const size_t offset = static_cast<size_t>(slices_written_) * info_.dims.nx * info_.dims.ny *
                          BytesPerVoxel(info_.dtype);
    SM_RETURN_IF_ERROR(Advance(count, data.size()));
    std::copy(data.begin(), data.end(), out_->data.begin() + offset);
    return absl::OkStatus();
  }
  absl::Status Finish() override { return CheckComplete(); }

 private:
  DenseVolume* out_;
};

nlohmann::json VecJson(const Vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

// A unit vector uniform on the sphere.
Vec3 RandomDirection(Rng& rng) {
  const double z = rng.Uniform(-1, 1), phi = rng.Uniform(0, 2 * kPi);
  const double r = std::sqrt(std::max(0.0, 1 - z * z));
  return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// Two sheets through `centre` meeting at options.junction_degrees along a line of random
// direction (the first sheet's normal random too): the first two of truth->sheets are
// turned so, the rest dropped; the junction is listed in the truth.
void PlaceJunction(Rng& rng, const Vec3& centre, PhantomTruth* truth) {
  const PhantomOptions& o = truth->options;
  truth->sheets.resize(2);
  Vec3 n0 = RandomDirection(rng);
  if (n0.z < 0) n0 = -n0;
  const Vec3 helper = std::abs(n0.z) < 0.9 ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
  const Vec3 e1 = Normalized(Cross(helper, n0)), e2 = Cross(n0, e1);
  const double az = rng.Uniform(0, 2 * kPi);
  const Vec3 line = e1 * std::cos(az) + e2 * std::sin(az);  // in sheet 0's plane
  const Vec3 across = Cross(line, n0);                        // in sheet 0's plane, across it
  const double angle = o.junction_degrees * kPi / 180;
  // Sheet 1's plane holds the line and leaves sheet 0's at `angle`.
  Vec3 n1 = n0 * std::cos(angle) + across * std::sin(angle);
  const Vec3 n[2] = {n0, n1.z < 0 ? -n1 : n1};
  for (int k = 0; k < 2; ++k) {
    PhantomSheet& s = truth->sheets[k];
    s.center = centre;
    s.normal = n[k];
    s.u = line;
    s.v = Cross(s.normal, s.u);
    s.has_cut = false;
  }
  if (o.junction_t) {
    // The stem (sheet 1) keeps the side of sheet 0 its v points to: its (a, b) with b >= 0.
    PhantomSheet& stem = truth->sheets[1];
    stem.has_cut = true;
    stem.cut_u = 0;
    stem.cut_v = 1;
  }
  PhantomJunction j;
  j.point = centre;
  j.direction = line;
  j.degrees = o.junction_degrees;
  j.t = o.junction_t;
  truth->junctions.push_back(j);
}

absl::StatusOr<PhantomTruth> PlanPhantom(const PhantomOptions& options) {
  SM_RETURN_IF_ERROR(Validate(options));
  PhantomTruth truth;
  truth.options = options;
  Rng rng(options.seed);
  const Dims& d = options.dims;
  const Vec3 centre(0.5 * (d.nx - 1), 0.5 * (d.ny - 1), 0.5 * (d.nz - 1));
  const double size = (d.nx + d.ny + d.nz) / 3.0;
  const double rad = kPi / 180.0;
  const int num_sheets =
      options.junction_degrees > 0 ? std::max(2, options.num_sheets) : options.num_sheets;
  for (int k = 0; k < num_sheets; ++k) {
    PhantomSheet s;
    const double dip = rng.Uniform(options.min_dip_degrees, options.max_dip_degrees) * rad;
    // Spread the dip directions so that sheets cross rather than stack.
    const double az = (360.0 * k / std::max(1, options.num_sheets) + rng.Uniform(0, 40)) * rad;
    s.normal =
        Normalized(Vec3(std::sin(dip) * std::sin(az), std::sin(dip) * std::cos(az), std::cos(dip)));
    s.center = centre + Vec3(rng.Uniform(-0.15, 0.15) * d.nx, rng.Uniform(-0.15, 0.15) * d.ny,
                             rng.Uniform(-0.15, 0.15) * d.nz);
    if (options.center_z_fraction >= 0) s.center.z = options.center_z_fraction * (d.nz - 1);
    const Vec3 helper = std::abs(s.normal.z) < 0.9 ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
    s.u = Normalized(Cross(helper, s.normal));
    s.v = Cross(s.normal, s.u);
    s.half_extent_u = options.extent_fraction * size * rng.Uniform(0.8, 1.2);
    s.half_extent_v = options.extent_fraction * size * rng.Uniform(0.8, 1.2);
    s.aperture_mean = options.aperture_voxels * rng.Uniform(0.85, 1.15);
    s.undulation = options.undulation_voxels;
    s.wall_roughness = options.wall_roughness_voxels;
    for (int h = 0; h < options.holes_per_sheet; ++h) {
      PhantomHole hole;
      hole.u = rng.Uniform(-0.55, 0.55) * s.half_extent_u;
      hole.v = rng.Uniform(-0.55, 0.55) * s.half_extent_v;
      hole.radius = options.hole_radius_fraction * std::min(s.half_extent_u, s.half_extent_v) *
                    rng.Uniform(0.7, 1.3);
      s.holes.push_back(hole);
    }
    if (k < options.fragmented_sheets) {
      for (int g = 0; g < 2; ++g) {
        PhantomGap gap;
        gap.angle = rng.Uniform(0, kPi);
        gap.offset = rng.Uniform(-0.4, 0.4) * std::min(s.half_extent_u, s.half_extent_v);
        gap.width = options.fragment_gap_voxels;
        s.gaps.push_back(gap);
      }
    }
    truth.sheets.push_back(std::move(s));
  }
  if (options.junction_degrees > 0) PlaceJunction(rng, centre, &truth);
  const int64_t specks = options.num_specks >= 0
                             ? options.num_specks
                             : std::max<int64_t>(1, d.num_voxels() / (20 * 20 * 20));
  for (int64_t k = 0; k < specks; ++k) {
    PhantomSpeck sp;
    sp.center = Vec3(rng.Uniform(0, d.nx - 1), rng.Uniform(0, d.ny - 1), rng.Uniform(0, d.nz - 1));
    sp.radius = options.speck_radius_voxels * rng.Uniform(0.6, 1.2);
    truth.specks.push_back(sp);
  }
  // Drawn last, so that the sheets and specks of a seed are the same with vugs or without.
  for (size_t k = 0; k < truth.sheets.size(); ++k) {
    const PhantomSheet& s = truth.sheets[k];
    for (int n = 0; n < options.vugs_per_sheet; ++n) {
      PhantomVug vug;
      vug.sheet = static_cast<int>(k);
      vug.center = s.center + s.u * (rng.Uniform(-0.5, 0.5) * s.half_extent_u) +
                   s.v * (rng.Uniform(-0.5, 0.5) * s.half_extent_v);
      vug.normal = s.normal;
      vug.radius_along = options.vug_radius_voxels * rng.Uniform(0.8, 1.2);
      vug.radius_across = 0.5 * vug.radius_along;
      truth.vugs.push_back(vug);
    }
  }
  return truth;
}

absl::Status GeneratePhantom(PhantomTruth* truth, VolumeSink& sink, const Progress& progress) {
  const PhantomOptions& o = truth->options;
  if (!(sink.info().dims == o.dims) || sink.info().dtype != o.dtype) {
    return absl::InvalidArgumentError(absl::StrCat(
        "phantom sink is ", sink.info().dims.ToString(), " ", DTypeName(sink.info().dtype),
        " but the phantom is ", o.dims.ToString(), " ", DTypeName(o.dtype)));
  }
  switch (o.dtype) {
    case DType::kUInt8:
      return Generate<uint8_t>(truth, sink, progress);
    case DType::kUInt16:
      return Generate<uint16_t>(truth, sink, progress);
    case DType::kFloat32:
      return Generate<float>(truth, sink, progress);
  }
  return absl::InternalError("unknown dtype");
}

absl::StatusOr<DenseVolume> GeneratePhantomDense(PhantomTruth* truth) {
  DenseVolume v = DenseVolume::Zeros(truth->options.dims, truth->options.dtype);
  v.info.format = "phantom";
  DenseSink sink(&v);
  SM_RETURN_IF_ERROR(GeneratePhantom(truth, sink));
  return v;
}

std::string PhantomTruth::ToJson() const {
  nlohmann::json j;
  const PhantomOptions& o = options;
  j["dims"] = {o.dims.nx, o.dims.ny, o.dims.nz};
  j["seed"] = o.seed;
  j["dtype"] = std::string(DTypeName(o.dtype));
  j["sheet_value"] = o.sheet_value;
  j["background_value"] = o.background_value;
  j["sheet_voxels"] = sheet_voxels;
  j["speck_voxels"] = speck_voxels;
  j["sheet_fraction"] = o.dims.num_voxels() > 0 ? double(sheet_voxels) / o.dims.num_voxels() : 0;
  nlohmann::json sheets = nlohmann::json::array();
  for (size_t k = 0; k < this->sheets.size(); ++k) {
    const PhantomSheet& s = this->sheets[k];
    const Orientation ori = OrientationOf(s.normal);
    nlohmann::json js;
    js["id"] = k;
    js["center"] = VecJson(s.center);
    js["normal"] = VecJson(s.normal);
    js["u"] = VecJson(s.u);
    js["v"] = VecJson(s.v);
    js["dip_degrees"] = ori.dip_degrees;
    js["dip_direction_degrees"] = ori.dip_direction_degrees;
    js["half_extent_u"] = s.half_extent_u;
    js["half_extent_v"] = s.half_extent_v;
    js["aperture"] = {{"mean", s.aperture_mean}, {"min", s.aperture_min}, {"max", s.aperture_max}};
    js["undulation"] = s.undulation;
    js["wall_roughness"] = s.wall_roughness;
    js["voxels"] = s.voxels;
    nlohmann::json holes = nlohmann::json::array();
    for (const PhantomHole& h : s.holes)
      holes.push_back({{"u", h.u}, {"v", h.v}, {"radius", h.radius}});
    js["holes"] = holes;
    nlohmann::json gaps = nlohmann::json::array();
    for (const PhantomGap& g : s.gaps) {
      gaps.push_back({{"angle", g.angle}, {"offset", g.offset}, {"width", g.width}});
    }
    js["gaps"] = gaps;
    sheets.push_back(js);
  }
  j["sheets"] = sheets;
  nlohmann::json vugs_json = nlohmann::json::array();
  for (const PhantomVug& v : vugs) {
    vugs_json.push_back({{"sheet", v.sheet},
                         {"center", VecJson(v.center)},
                         {"radius_along", v.radius_along},
                         {"radius_across", v.radius_across}});
  }
  j["vugs"] = vugs_json;
  nlohmann::json junctions_json = nlohmann::json::array();
  for (const PhantomJunction& jn : junctions) {
    junctions_json.push_back({{"point", VecJson(jn.point)},
                              {"direction", VecJson(jn.direction)},
                              {"degrees", jn.degrees},
                              {"sheets", {jn.sheet_a, jn.sheet_b}},
                              {"kind", jn.t ? "t" : "x"}});
  }
  j["junctions"] = junctions_json;
  nlohmann::json specks_json = nlohmann::json::array();
  for (const PhantomSpeck& sp : specks) {
    specks_json.push_back({{"center", VecJson(sp.center)}, {"radius", sp.radius}});
  }
  j["specks"] = specks_json;
  return JsonText(j, 2);
}

}  // namespace sheetmesh
