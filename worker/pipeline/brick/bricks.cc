#include "worker/pipeline/brick/bricks.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <tuple>
#include <nlohmann/json.hpp>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/run/parameters.h"
#include "worker/pipeline/volume/nrrd_io.h"
#include "worker/pipeline/voxel/threshold.h"

namespace sheetmesh {
namespace {

constexpr char kPlanFormat[] = "sheetmesh brick plan 1";
constexpr char kBrickMagic[8] = {'S', 'M', 'B', 'R', 'I', 'C', 'K', '1'};

// FNV-1a, 64 bits: the plan's fingerprint in each brick and each brick file's checksum.
uint64_t Fnv1a(const void* data, size_t n, uint64_t h = 0xcbf29ce484222325ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

// Sorted, with ranges that touch or overlap joined.
std::vector<FileRange> Joined(std::vector<FileRange> ranges) {
  std::sort(ranges.begin(), ranges.end(),
            [](const FileRange& a, const FileRange& b) { return a.offset < b.offset; });
  std::vector<FileRange> out;
  for (const FileRange& r : ranges) {
    if (r.length <= 0) continue;
    if (!out.empty() && r.offset <= out.back().offset + out.back().length) {
      out.back().length = std::max(out.back().length, r.offset + r.length - out.back().offset);
    } else {
      out.push_back(r);
    }
  }
  return out;
}

nlohmann::json RegionJson(const VoxelRegion& r) {
  return {r.lo.x, r.lo.y, r.lo.z, r.hi.x, r.hi.y, r.hi.z};
}

// Cuts [0, n) at origin + k * size.
std::vector<std::pair<int32_t, int32_t>> Cuts(int64_t n, int32_t size, int32_t origin) {
  std::vector<std::pair<int32_t, int32_t>> out;
  int64_t lo = 0;
  int64_t next = origin > 0 ? origin : size;
  while (lo < n) {
    const int64_t hi = std::min<int64_t>(n, next);
    out.emplace_back(static_cast<int32_t>(lo), static_cast<int32_t>(hi));
    lo = hi;
    next = hi + size;
  }
  return out;
}

// The job's options as the plan holds them, on the volume (and brick) given.
absl::StatusOr<PipelineOptions> PlanOptions(const BrickPlan& plan, const std::string& source) {
  ParameterBuilder builder;
  SM_RETURN_IF_ERROR(builder.AddJson(plan.parameters, source));
  SM_ASSIGN_OR_RETURN(PipelineOptions o, builder.Build());
  o.input.path = plan.volume;
  return o;
}

void PutU64(std::string* s, uint64_t v) { s->append(reinterpret_cast<const char*>(&v), 8); }
void PutI32(std::string* s, int32_t v) { s->append(reinterpret_cast<const char*>(&v), 4); }
void PutF64(std::string* s, double v) { s->append(reinterpret_cast<const char*>(&v), 8); }

// Reads the brick file's fields in order; false once past the end.
class Cursor {
 public:
  explicit Cursor(absl::string_view data) : data_(data) {}
  template <class T>
  bool Get(T* v) {
    if (pos_ + sizeof(T) > data_.size()) return false;
    std::memcpy(v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }

 private:
  absl::string_view data_;
  size_t pos_ = 0;
};

}  // namespace

std::string PlanFile(const std::string& plan_dir) {
  return (std::filesystem::path(plan_dir) / "plan.json").string();
}

std::string BrickFile(const std::string& plan_dir, int index) {
  return (std::filesystem::path(plan_dir) / "bricks" / absl::StrFormat("brick_%06d.bin", index))
      .string();
}

std::string BrickPlan::ToJson() const {
  nlohmann::json j;
  j["format"] = kPlanFormat;
  j["volume"] = volume;
  j["parameters"] = nlohmann::json::parse(parameters);
  j["dims"] = {info.dims.nx, info.dims.ny, info.dims.nz};
  j["dtype"] = std::string(DTypeName(info.dtype));
  j["volume_format"] = info.format;
  const Placement& p = info.placement;
  j["spacing"] = {p.spacing.x, p.spacing.y, p.spacing.z};
  j["origin"] = {p.origin.x, p.origin.y, p.origin.z};
  j["unit"] = p.unit;
  j["brick_size"] = {grid.size.x, grid.size.y, grid.size.z};
  j["grid_origin"] = {grid.origin.x, grid.origin.y, grid.origin.z};
  if (otsu) j["otsu_threshold"] = *otsu;
  j["halo"] = halo;
  j["in_bricks"] = in_bricks;
  nlohmann::json list = nlohmann::json::array();
  for (const Brick& b : bricks) {
    nlohmann::json brick = {
        {"index", b.index}, {"core", RegionJson(b.core)}, {"read", RegionJson(b.read)}};
    if (!b.fetch.empty()) {
      nlohmann::json fetch = nlohmann::json::array();
      for (const FileRange& r : b.fetch) fetch.push_back({r.offset, r.length});
      brick["fetch"] = std::move(fetch);
    }
    list.push_back(std::move(brick));
  }
  j["bricks"] = std::move(list);
  return j.dump(1) + "\n";
}

absl::Status CheckBrickCount(const Dims& dims, const BrickGrid& grid, absl::string_view what) {
  const int32_t size[3] = {grid.size.x, grid.size.y, grid.size.z};
  const int32_t origin[3] = {grid.origin.x, grid.origin.y, grid.origin.z};
  const int64_t n[3] = {dims.nx, dims.ny, dims.nz};
  int64_t count = 1;
  for (int k = 0; k < 3; ++k) {
    if (size[k] < 1) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, " ", size[k], " along ", std::string(1, "xyz"[k]), " is below 1"));
    }
    // Cells from the one holding voxel 0 to the one holding voxel n - 1 (origin in [0, size)).
    const int64_t along = (n[k] - 1 + (size[k] - origin[k] % size[k]) % size[k]) / size[k] + 1;
    count = std::min<int64_t>(count * along, kMaxPlanBricks + 1);
  }
  if (count > kMaxPlanBricks) {
    return absl::InvalidArgumentError(absl::StrCat(
        what, " ", size[0], "x", size[1], "x", size[2], " cuts the volume's ", dims.ToString(),
        " into more than ", kMaxPlanBricks, " bricks: give larger bricks"));
  }
  return absl::OkStatus();
}

absl::StatusOr<Index3> ParseBrickSize(const std::string& text, const std::string& field) {
  if (text == "auto") return Index3{0, 0, 0};
  int32_t n = 0;
  if (absl::SimpleAtoi(text, &n)) return Index3{n, n, n};
  const std::vector<std::string> parts = absl::StrSplit(text, 'x');
  Index3 size;
  if (parts.size() != 3 || !absl::SimpleAtoi(parts[0], &size.x) ||
      !absl::SimpleAtoi(parts[1], &size.y) || !absl::SimpleAtoi(parts[2], &size.z)) {
    return absl::InvalidArgumentError(absl::StrCat(
        field, " '", text, "' is not a brick size: \"auto\", \"512\" or \"512x512x256\""));
  }
  return size;
}

std::optional<std::vector<FileRange>> PlanReads(const PipelineOptions& options) {
  if (options.input.threshold == "otsu" || options.input.open.region) return std::nullopt;
  const absl::StatusOr<std::string> format = InputFormatOf(options.input.path, options.input.open);
  if (!format.ok()) return std::nullopt;
  if (*format == "raw") return std::vector<FileRange>{};
  if (*format == "nrrd") return std::vector<FileRange>{{0, kNrrdMaxHeaderBytes}};
  return std::nullopt;
}

absl::StatusOr<BrickPlan> MakeBrickPlan(const PipelineOptions& options,
                                        const BrickGrid& requested) {
  BrickGrid grid = requested;
  const int32_t given[3] = {grid.size.x, grid.size.y, grid.size.z};
  for (int k = 0; k < 3; ++k) {
    if (given[k] < 0) {
      return absl::InvalidArgumentError(absl::StrCat("brick_size ", given[k], " along ",
                                                     std::string(1, "xyz"[k]),
                                                     " must be a voxel count (or 0: chosen)"));
    }
  }
  // The volume's dims first: a chosen edge follows them.
  std::error_code ec;
  const std::string volume =
      std::filesystem::absolute(options.input.path, ec).lexically_normal().string();
  SM_ASSIGN_OR_RETURN(const std::unique_ptr<VolumeSource> opened,
                      OpenVolume(volume, options.input.open));
  const VolumeInfo info = opened->info();
  const Dims& d = info.dims;
  const auto clamp32 = [](int64_t v) {
    return static_cast<int32_t>(std::clamp<int64_t>(v, 1, INT32_MAX));
  };
  if (grid.size.x == 0) grid.size.x = clamp32(d.nx);
  if (grid.size.y == 0) grid.size.y = clamp32(d.ny);
  if (grid.size.z == 0) {
    grid.size.z = clamp32(std::min<int64_t>(
        d.nz, kAutoBrickVoxels / std::max<int64_t>(1, int64_t{grid.size.x} * grid.size.y)));
  }
  const int32_t size[3] = {grid.size.x, grid.size.y, grid.size.z};
  const int32_t origin[3] = {grid.origin.x, grid.origin.y, grid.origin.z};
  BrickPlan plan;
  // Selection is per voxel: the stages bricks run now need no voxel around their core.
  plan.halo = 0;
  plan.in_bricks = {"read", "select"};
  for (int k = 0; k < 3; ++k) {
    if (size[k] < 1 || size[k] < 2 * plan.halo) {
      return absl::InvalidArgumentError(
          absl::StrCat("brick_size ", size[k], " along ", std::string(1, "xyz"[k]), " is below ",
                       std::max(1, 2 * plan.halo), " (at least one voxel, and twice the halo of ",
                       plan.halo, " voxels the bricked stages need)"));
    }
    if (origin[k] < 0 || origin[k] >= size[k]) {
      return absl::InvalidArgumentError(absl::StrCat("grid_origin ", origin[k], " along ",
                                                     std::string(1, "xyz"[k]), " must be in [0, ",
                                                     size[k], "), the brick size"));
    }
  }
  if (options.grey.enabled) {
    return absl::InvalidArgumentError(
        "input.grey finds sheets by their neighbourhood in the grey levels, which bricks do not "
        "run yet: run the job in one process");
  }
  if (options.input.open.region) {
    return absl::InvalidArgumentError(
        "input.region and bricks both choose what to read: plan the region as its own volume "
        "(sheetmesh-pipeline convert VOLUME --region=... -o REGION.h5)");
  }
  if (options.input.threshold == "otsu") {
    // The whole volume's histogram, before any brick selects: one pass, slab by slab.
    SM_ASSIGN_OR_RETURN(auto source, OpenVolume(volume, options.input.open));
    SM_ASSIGN_OR_RETURN(plan.otsu, OtsuThreshold(*source));
  }
  plan.volume = volume;
  PipelineOptions o = options;
  if (!o.input.mask_path.empty()) {
    o.input.mask_path = std::filesystem::absolute(o.input.mask_path, ec).string();
  }
  plan.parameters = CanonicalParametersJson(o, /*include_local=*/true);
  plan.info = info;
  plan.grid = grid;
  SM_RETURN_IF_ERROR(CheckBrickCount(d, grid, "brick_size"));
  const auto xs = Cuts(d.nx, size[0], origin[0]);
  const auto ys = Cuts(d.ny, size[1], origin[1]);
  const auto zs = Cuts(d.nz, size[2], origin[2]);
  for (const auto& [z0, z1] : zs) {
    for (const auto& [y0, y1] : ys) {
      for (const auto& [x0, x1] : xs) {
        Brick b;
        b.index = static_cast<int>(plan.bricks.size());
        b.core = {{x0, y0, z0}, {x1, y1, z1}};
        const int32_t h = plan.halo;
        const auto clip = [](int64_t v, int64_t n) {
          return static_cast<int32_t>(std::clamp<int64_t>(v, 0, n));
        };
        b.read = {{clip(x0 - h, d.nx), clip(y0 - h, d.ny), clip(z0 - h, d.nz)},
                  {clip(x1 + h, d.nx), clip(y1 + h, d.ny), clip(z1 + h, d.nz)}};
        if (auto bytes = opened->BytesRead(b.read.lo.z, b.read.hi.z - b.read.lo.z)) {
          b.fetch = Joined(*std::move(bytes));
        }
        plan.bricks.push_back(b);
      }
    }
  }
  const std::string text = plan.ToJson();  // as WriteBrickPlan writes it
  plan.fingerprint = Fnv1a(text.data(), text.size());
  return plan;
}

absl::Status WriteBrickPlan(const BrickPlan& plan, const std::string& plan_dir) {
  SM_RETURN_IF_ERROR(MakeDirs(plan_dir));
  const std::string text = plan.ToJson();
  const std::string path = PlanFile(plan_dir);
  absl::StatusOr<std::string> old = ReadFileToString(path);
  const std::string bricks = (std::filesystem::path(plan_dir) / "bricks").string();
  std::error_code ec;
  if (old.ok() && *old != text && std::filesystem::exists(bricks, ec) &&
      !std::filesystem::is_empty(bricks, ec)) {
    return absl::FailedPreconditionError(
        absl::StrCat(plan_dir, " holds the bricks of another plan: give a new folder, or remove ",
                     bricks, " first"));
  }
  SM_RETURN_IF_ERROR(MakeDirs(bricks));
  return WriteFileAtomically(path, text);
}

// A plan read back is checked whole before anything is sized from it: its dims within a
// volume's limits, its grid within kMaxPlanBricks, and its bricks the grid's cells, each
// inside the volume, tiling it once (a plan of 1048576^3 voxels in bricks of 1 made the
// merge allocate a row table beyond any memory).
absl::Status CheckPlanSizes(const BrickPlan& plan, const std::string& path) {
  const Dims& d = plan.info.dims;
  SM_RETURN_IF_ERROR(CheckDims(d, plan.info.dtype, VolumeLimits{}, path + ": dims"));
  SM_RETURN_IF_ERROR(CheckBrickCount(d, plan.grid, path + ": brick_size"));
  const int32_t size[3] = {plan.grid.size.x, plan.grid.size.y, plan.grid.size.z};
  const int32_t origin[3] = {plan.grid.origin.x, plan.grid.origin.y, plan.grid.origin.z};
  for (int k = 0; k < 3; ++k) {
    if (origin[k] < 0 || origin[k] >= size[k]) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": grid_origin ", origin[k], " along ",
                                                     std::string(1, "xyz"[k]), " is not in [0, ",
                                                     size[k], ")"));
    }
  }
  if (plan.halo < 0 || plan.halo > (1 << 20)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": halo ", plan.halo));
  }
  const auto inside = [&](const VoxelRegion& r) {
    return r.lo.x >= 0 && r.lo.y >= 0 && r.lo.z >= 0 && r.lo.x < r.hi.x && r.lo.y < r.hi.y &&
           r.lo.z < r.hi.z && r.hi.x <= d.nx && r.hi.y <= d.ny && r.hi.z <= d.nz;
  };
  const auto on_grid = [&](int32_t v, int k, int64_t n) {
    return v == 0 || v == n || (v - origin[k]) % size[k] == 0;
  };
  int64_t voxels = 0;
  absl::flat_hash_set<std::tuple<int32_t, int32_t, int32_t>> corners;
  for (size_t i = 0; i < plan.bricks.size(); ++i) {
    const Brick& b = plan.bricks[i];
    const VoxelRegion& c = b.core;
    const bool aligned = on_grid(c.lo.x, 0, d.nx) && on_grid(c.lo.y, 1, d.ny) &&
                         on_grid(c.lo.z, 2, d.nz) && on_grid(c.hi.x, 0, d.nx) &&
                         on_grid(c.hi.y, 1, d.ny) && on_grid(c.hi.z, 2, d.nz);
    const bool reads_core = b.read.lo.x <= c.lo.x && b.read.lo.y <= c.lo.y &&
                            b.read.lo.z <= c.lo.z && b.read.hi.x >= c.hi.x &&
                            b.read.hi.y >= c.hi.y && b.read.hi.z >= c.hi.z;
    if (!inside(c) || !inside(b.read) || !aligned || !reads_core ||
        !corners.insert({c.lo.x, c.lo.y, c.lo.z}).second) {
      return absl::InvalidArgumentError(absl::StrCat(
          path, ": bricks[", i, "] (core ", c.ToString(), ", read ", b.read.ToString(),
          ") is not a cell of the plan's grid inside its ", d.ToString(), " volume"));
    }
    voxels += c.dims().num_voxels();
  }
  if (voxels != d.num_voxels()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": its ", plan.bricks.size(),
                                                   " bricks hold ", voxels, " voxels of the ",
                                                   d.num_voxels(), " of its volume"));
  }
  return absl::OkStatus();
}

absl::StatusOr<BrickPlan> ReadBrickPlan(const std::string& plan_dir) {
  const std::string path = PlanFile(plan_dir);
  SM_ASSIGN_OR_RETURN(const std::string text, ReadFileToString(path));
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object() || j.value("format", "") != kPlanFormat) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a brick plan (its \"format\" is not \"", kPlanFormat,
                     "\"); sheetmesh-pipeline plan writes one"));
  }
  BrickPlan plan;
  plan.fingerprint = Fnv1a(text.data(), text.size());
  try {
    plan.volume = j.at("volume").get<std::string>();
    plan.parameters = j.at("parameters").dump();
    const auto& d = j.at("dims");
    plan.info.dims = {d.at(0).get<int64_t>(), d.at(1).get<int64_t>(), d.at(2).get<int64_t>()};
    SM_ASSIGN_OR_RETURN(plan.info.dtype, ParseDType(j.at("dtype").get<std::string>()));
    plan.info.format = j.at("volume_format").get<std::string>();
    const auto vec = [](const nlohmann::json& v) {
      return Vec3(v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>());
    };
    plan.info.placement.spacing = vec(j.at("spacing"));
    plan.info.placement.origin = vec(j.at("origin"));
    plan.info.placement.unit = j.at("unit").get<std::string>();
    const auto& s = j.at("brick_size");
    plan.grid.size = {s.at(0).get<int32_t>(), s.at(1).get<int32_t>(), s.at(2).get<int32_t>()};
    const auto& g = j.at("grid_origin");
    plan.grid.origin = {g.at(0).get<int32_t>(), g.at(1).get<int32_t>(), g.at(2).get<int32_t>()};
    if (j.contains("otsu_threshold")) plan.otsu = j.at("otsu_threshold").get<double>();
    plan.halo = j.at("halo").get<int>();
    plan.in_bricks = j.at("in_bricks").get<std::vector<std::string>>();
    const auto region = [](const nlohmann::json& r) {
      return VoxelRegion{{r.at(0).get<int32_t>(), r.at(1).get<int32_t>(), r.at(2).get<int32_t>()},
                         {r.at(3).get<int32_t>(), r.at(4).get<int32_t>(), r.at(5).get<int32_t>()}};
    };
    for (const auto& b : j.at("bricks")) {
      Brick brick{b.at("index").get<int>(), region(b.at("core")), region(b.at("read")), {}};
      if (b.contains("fetch")) {
        for (const auto& r : b.at("fetch")) {
          const FileRange range{r.at(0).get<int64_t>(), r.at(1).get<int64_t>()};
          if (range.offset < 0 || range.length <= 0) {
            return absl::InvalidArgumentError(absl::StrCat(
                path, ": bricks[", plan.bricks.size(), "].fetch holds the range ", range.offset,
                " + ", range.length, " (an offset of 0 or more and a positive length)"));
          }
          brick.fetch.push_back(range);
        }
      }
      plan.bricks.push_back(std::move(brick));
    }
  } catch (const nlohmann::json::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path,
                                                   ": a field is missing or of the wrong "
                                                   "type: ",
                                                   e.what()));
  }
  for (size_t i = 0; i < plan.bricks.size(); ++i) {
    if (plan.bricks[i].index != static_cast<int>(i)) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": bricks[", i, "].index is ", plan.bricks[i].index, ", not ", i));
    }
  }
  SM_RETURN_IF_ERROR(CheckPlanSizes(plan, path));
  return plan;
}

absl::StatusOr<BrickResult> RunBrick(const std::string& plan_dir, int index,
                                     const Progress& progress, const BrickSite& site) {
  SM_ASSIGN_OR_RETURN(BrickPlan plan, ReadBrickPlan(plan_dir));
  if (!site.volume.empty()) plan.volume = site.volume;
  if (index < 0 || index >= static_cast<int>(plan.bricks.size())) {
    return absl::InvalidArgumentError(absl::StrCat("brick index ", index, " is outside the plan's ",
                                                   plan.bricks.size(), " bricks (0 to ",
                                                   plan.bricks.size() - 1, ")"));
  }
  const Brick& brick = plan.bricks[index];
  SM_ASSIGN_OR_RETURN(PipelineOptions o, PlanOptions(plan, PlanFile(plan_dir)));
  if (site.limits) o.input.open.limits = *site.limits;
  o.input.open.child_reader = site.child_reader;
  const SheetInput& in = o.input;
  // The volume must still be the one planned: a file replaced since would mix two volumes.
  // Opened once, checked, then seen through the brick's box.
  SM_ASSIGN_OR_RETURN(auto whole, OpenVolume(plan.volume, in.open));
  if (!(whole->info().dims == plan.info.dims) || whole->info().dtype != plan.info.dtype) {
    return absl::FailedPreconditionError(
        absl::StrCat(plan.volume, " is ", whole->info().dims.ToString(), " ",
                     DTypeName(whole->info().dtype), " now, and the plan was made for ",
                     plan.info.dims.ToString(), " ", DTypeName(plan.info.dtype), ": plan again"));
  }
  SM_ASSIGN_OR_RETURN(auto source, OpenRegion(std::move(whole), brick.read));
  BrickResult out;
  out.index = index;
  out.core = brick.core;
  std::optional<VoxelSet> mask;
  if (!in.mask_path.empty() || in.mask_from_volume) {
    OpenOptions region = in.open;
    region.region = brick.read;
    SM_ASSIGN_OR_RETURN(auto msource,
                        OpenVolume(in.mask_from_volume ? in.path : in.mask_path, region));
    SM_ASSIGN_OR_RETURN(
        mask, SelectPhase(*msource, in.mask_selection, nullptr, nullptr, progress.Sub(0, 0.5)));
  }
  std::optional<double> threshold;
  SM_ASSIGN_OR_RETURN(const PhaseSelection selection, StatedSelection(in, &threshold, plan.otsu));
  SM_ASSIGN_OR_RETURN(VoxelSet local,
                      SelectPhase(*source, selection, mask ? &*mask : nullptr, &out.stats,
                                  mask ? progress.Sub(0.5, 1) : progress));
  // The core's voxels, in the core's coordinates.
  const VoxelRegion& r = brick.read;
  const VoxelRegion& core = brick.core;
  VoxelSet::Builder builder(core.dims());
  local.ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t) {
    const int64_t gy = y + r.lo.y, gz = z + r.lo.z;
    if (gy < brick.core.lo.y || gy >= brick.core.hi.y || gz < brick.core.lo.z ||
        gz >= brick.core.hi.z) {
      return;
    }
    const int64_t x0 = std::max<int64_t>(run.x0 + r.lo.x, core.lo.x);
    const int64_t x1 = std::min<int64_t>(run.x1 + r.lo.x, core.hi.x);
    if (x0 < x1) builder.AddRun(gy - core.lo.y, gz - core.lo.z, x0 - core.lo.x, x1 - core.lo.x);
  });
  out.sheet = std::move(builder).Build();
  out.plan_hash = plan.fingerprint;
  // The file: magic, plan hash, index, core, stats, runs (y, z, x0, x1 in the volume's
  // coordinates), checksum.
  std::string bytes(kBrickMagic, sizeof(kBrickMagic));
  PutU64(&bytes, out.plan_hash);
  PutI32(&bytes, index);
  for (const int32_t v : {brick.core.lo.x, brick.core.lo.y, brick.core.lo.z, brick.core.hi.x,
                          brick.core.hi.y, brick.core.hi.z}) {
    PutI32(&bytes, v);
  }
  PutF64(&bytes, out.stats.min_value);
  PutF64(&bytes, out.stats.max_value);
  PutU64(&bytes, out.stats.selected);
  PutU64(&bytes, out.stats.outside_mask);
  PutU64(&bytes, static_cast<uint64_t>(out.sheet.num_runs()));
  out.sheet.ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t) {
    for (const int32_t v : {y + core.lo.y, z + core.lo.z, run.x0 + core.lo.x, run.x1 + core.lo.x}) {
      PutI32(&bytes, v);
    }
  });
  PutU64(&bytes, Fnv1a(bytes.data(), bytes.size()));
  out.file_bytes = bytes.size();
  SM_RETURN_IF_ERROR(WriteFileAtomically(BrickFile(plan_dir, index), bytes));
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

absl::StatusOr<BrickResult> ReadBrick(const std::string& plan_dir, const BrickPlan& plan,
                                      int index) {
  const std::string path = BrickFile(plan_dir, index);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return absl::NotFoundError(absl::StrCat("brick ", index, " has not run (no ", path, ")"));
  }
  SM_ASSIGN_OR_RETURN(const std::string bytes, ReadFileToString(path, int64_t{1} << 40));
  const auto damaged = [&](absl::string_view what) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": ", what, "; run the brick again (sheetmesh-pipeline brick ", plan_dir,
                     " --index=", index, ")"));
  };
  if (bytes.size() < sizeof(kBrickMagic) + 8 ||
      std::memcmp(bytes.data(), kBrickMagic, sizeof(kBrickMagic)) != 0) {
    return damaged("not a brick file");
  }
  uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  if (stored != Fnv1a(bytes.data(), bytes.size() - 8))
    return damaged("its checksum does not match");
  Cursor c(absl::string_view(bytes).substr(sizeof(kBrickMagic), bytes.size() - 8 - 8));
  BrickResult out;
  out.file_bytes = bytes.size();
  int32_t box[6];
  uint64_t runs = 0;
  bool ok = c.Get(&out.plan_hash) && c.Get(&out.index);
  for (int k = 0; k < 6; ++k) ok = ok && c.Get(&box[k]);
  ok = ok && c.Get(&out.stats.min_value) && c.Get(&out.stats.max_value) &&
       c.Get(&out.stats.selected) && c.Get(&out.stats.outside_mask) && c.Get(&runs);
  if (!ok) return damaged("it ends inside its header");
  if (out.plan_hash != plan.fingerprint) {
    return damaged("it was made from another plan.json");
  }
  out.core = {{box[0], box[1], box[2]}, {box[3], box[4], box[5]}};
  if (out.index != index || !(out.core == plan.bricks[index].core)) {
    return damaged("its index or box is not the plan's");
  }
  const VoxelRegion& core = out.core;
  VoxelSet::Builder builder(core.dims());
  int64_t last_row = -1, last_x1 = 0;
  for (uint64_t i = 0; i < runs; ++i) {
    int32_t y, z, x0, x1;
    if (!(c.Get(&y) && c.Get(&z) && c.Get(&x0) && c.Get(&x1))) return damaged("it ends early");
    if (y < core.lo.y || y >= core.hi.y || z < core.lo.z || z >= core.hi.z || x0 < core.lo.x ||
        x1 > core.hi.x || x0 >= x1) {
      return damaged(absl::StrCat("run ", i, " (y ", y, ", z ", z, ", x ", x0, " to ", x1,
                                  ") lies outside its box"));
    }
    const int64_t row = (int64_t{z} - core.lo.z) * (core.hi.y - core.lo.y) + (y - core.lo.y);
    if (row < last_row || (row == last_row && x0 <= last_x1)) {
      return damaged(absl::StrCat("run ", i, " is out of order"));
    }
    last_row = row;
    last_x1 = x1;
    builder.AddRun(y - core.lo.y, z - core.lo.z, x0 - core.lo.x, x1 - core.lo.x);
  }
  out.sheet = std::move(builder).Build();
  return out;
}

}  // namespace sheetmesh
