// The table of parameters: one row per setting of PipelineOptions. Adding a parameter is
// one row here (and its proto field; the tests check that both exist and agree).
#include "absl/strings/str_cat.h"
#include "worker/pipeline/run/parameter_row_helpers.h"
#include "worker/pipeline/voxel/threshold.h"

namespace sheetmesh {
namespace {

using namespace parameter_rows;  // NOLINT: the table's own vocabulary

std::vector<ParamRow> InputRows() {
  std::vector<ParamRow> rows;
  rows.push_back(Choice("input.format", SM_MEMBER(input.open.format),
                        {{"auto", ""},
                         {"raw", "raw"},
                         {"tiff", "tiff"},
                         {"png", "png"},
                         {"jpeg", "jpeg"},
                         {"dicom", "dicom"},
                         {"folder", "folder"},
                         {"nrrd", "nrrd"},
                         {"vdb", "vdb"},
                         {"npy", "npy"},
                         {"mrc", "mrc"},
                         {"nifti", "nifti"},
                         {"hdf5", "hdf5"}},
                        "volume format; auto: by the file's extension (a folder: its TIFF, PNG, "
                        "JPEG or DICOM slices; file.h5:/dataset: HDF5)"));
  {
    ParamRow r = Row("input.dims", ParamType::kIntegers, "[1, 1048576]", "voxels",
                     "raw volumes: NX, NY, NZ (default: from a name like a_64x64x32_u8.raw)");
    r.spec.count = 3;
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      const std::optional<Dims>& d = o.input.open.raw_dims;
      if (!d) return std::nullopt;
      return ParamValue(std::vector<int64_t>{d->nx, d->ny, d->nz});
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      const auto& d = std::get<std::vector<int64_t>>(v);
      o.input.open.raw_dims = Dims{d[0], d[1], d[2]};
    };
    rows.push_back(std::move(r));
  }
  {
    ParamRow r = Row("input.dtype", ParamType::kChoice, nullptr, "",
                     "raw volumes: voxel type (default uint8, or the name's _u8/_u16/_f32)");
    r.spec.choices = {"uint8", "uint16", "float32"};
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      if (!o.input.open.raw_dtype) return std::nullopt;
      return ParamValue(std::string(DTypeName(*o.input.open.raw_dtype)));
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      o.input.open.raw_dtype = *ParseDType(std::get<std::string>(v));
    };
    rows.push_back(std::move(r));
  }
  {
    ParamRow r = Row("input.region", ParamType::kIntegers, "[0, 1048576]", "voxels",
                     "read only this box of the volume, X0, Y0, Z0, X1, Y1, Z1 (voxels x in "
                     "[X0, X1), ...): a region of interest; only its slices are read, and the "
                     "meshes keep the volume's coordinates");
    r.spec.count = 6;
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      const std::optional<VoxelRegion>& b = o.input.open.region;
      if (!b) return std::nullopt;
      return ParamValue(std::vector<int64_t>{b->lo.x, b->lo.y, b->lo.z, b->hi.x, b->hi.y, b->hi.z});
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      const auto& b = std::get<std::vector<int64_t>>(v);
      const auto i = [&](int k) { return static_cast<int32_t>(b[k]); };
      o.input.open.region = VoxelRegion{{i(0), i(1), i(2)}, {i(3), i(4), i(5)}};
    };
    r.check = [](const ParamValue& v) -> std::string {
      const auto& b = std::get<std::vector<int64_t>>(v);
      for (int k = 0; k < 3; ++k) {
        if (b[k] >= b[k + 3]) return "must give X0 < X1, Y0 < Y1 and Z0 < Z1";
      }
      return "";
    };
    rows.push_back(std::move(r));
  }
  rows.push_back(Choice("input.byte_order", SM_MEMBER(input.open.raw_byte_order),
                        {{"little", ByteOrder::kLittle}, {"big", ByteOrder::kBig}},
                        "raw volumes: byte order of 16- and 32-bit voxels"));
  rows.push_back(Integer("input.header_bytes", SM_MEMBER(input.open.raw_header_bytes),
                         "[0, 1099511627776]", "bytes", "raw volumes: bytes before the voxels"));
  rows.push_back(Text("input.vdb_grid", SM_MEMBER(input.open.vdb_grid),
                      "vdb volumes: the grid to read (empty: the first scalar grid)"));
  rows.push_back(Triple("input.spacing", &OpenOptions::spacing, "[1e-12, 1e9]", "unit",
                        "voxel size x, y, z overriding the file's"));
  rows.push_back(Triple("input.origin", &OpenOptions::origin, "[-1e15, 1e15]", "unit",
                        "position of voxel (0, 0, 0) overriding the file's"));
  rows.push_back(Text("input.unit", SM_MEMBER(input.open.unit),
                      "length unit overriding the file's (mm, um, ...)"));
  rows.push_back(
      Local(Integer("input.max_voxels", SM_MEMBER(input.open.limits.max_voxels),
                    "[1, 1099511627776]", "voxels", "volumes with more voxels are refused")));
  rows.push_back(Exclusive(Labels("input.labels", &SheetInput::selection,
                                  "sheet phase: these voxel values (default: every non-zero "
                                  "voxel)"),
                           "selection"));
  {
    ParamRow r = Exclusive(Text("input.threshold", SM_MEMBER(input.threshold),
                                "sheet phase of a grayscale scan: otsu (Otsu's threshold of "
                                "the volume) or a value; the voxels below it (dark: open "
                                "fractures) unless input.threshold_above"),
                           "selection");
    // Unset when empty: only a threshold given excludes the labels and the window.
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      if (o.input.threshold.empty()) return std::nullopt;
      return ParamValue(o.input.threshold);
    };
    r.check = [](const ParamValue& v) -> std::string {
      const std::string& t = std::get<std::string>(v);
      return t.empty() || ParseThreshold(t).ok() ? "" : "must be otsu or a number";
    };
    rows.push_back(std::move(r));
  }
  rows.push_back(Bool("input.threshold_above", SM_MEMBER(input.threshold_above),
                      "with input.threshold: the voxels at or above it (bright: mineral "
                      "veins)"));
  {
    ParamRow r = Row("input.window", ParamType::kNumbers, "[-1e300, 1e300]", "",
                     "sheet phase: values in [LO, HI] (--window=LO:HI)");
    r.spec.count = 2;
    r.spec.exclusive = "selection";
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      const PhaseSelection& s = o.input.selection;
      if (s.mode != PhaseSelection::Mode::kWindow) return std::nullopt;
      return ParamValue(std::vector<double>{s.lo, s.hi});
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      const auto& w = std::get<std::vector<double>>(v);
      o.input.selection = PhaseSelection::Window(w[0], w[1]);
    };
    r.check = [](const ParamValue& v) -> std::string {
      const auto& w = std::get<std::vector<double>>(v);
      return w[0] <= w[1] ? "" : "must be [lo, hi] with lo <= hi";
    };
    rows.push_back(std::move(r));
  }
  {
    ParamRow r = Row("input.grey", ParamType::kBool, nullptr, "",
                     "sheet phase of a grey scan as it came: sheets found by their sheetness, "
                     "apertures from the attenuation they miss (grey.*)");
    r.spec.exclusive = "selection";
    // Unset when off: only a grey run excludes the labels, the window and the threshold.
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      if (!o.grey.enabled) return std::nullopt;
      return ParamValue(true);
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) { o.grey.enabled = std::get<bool>(v); };
    rows.push_back(std::move(r));
  }
  rows.push_back(Local(Text("input.mask", SM_MEMBER(input.mask_path),
                            "rock mask volume, same dims (non-zero = rock; empty: none)")));
  rows.push_back(Labels("input.mask_labels", &SheetInput::mask_selection,
                        "rock mask: the values that are rock (default: non-zero)"));
  return rows;
}

// input.grey's settings.
std::vector<ParamRow> GreyRows() {
  std::vector<ParamRow> rows;
  {
    ParamRow r = Row("grey.levels", ParamType::kNumbers, "[-1e300, 1e300]", "",
                     "grey levels of the void and the rock, [VOID, ROCK] (unset: measured from "
                     "the histogram's peaks)");
    r.spec.count = 2;
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      if (o.grey.levels.empty()) return std::nullopt;
      return ParamValue(o.grey.levels);
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      o.grey.levels = std::get<std::vector<double>>(v);
    };
    r.check = [](const ParamValue& v) -> std::string {
      const auto& w = std::get<std::vector<double>>(v);
      return w[0] < w[1] ? "" : "must be [VOID, ROCK] with the void darker";
    };
    rows.push_back(std::move(r));
  }
  rows.push_back(Number("grey.psf_sigma", SM_MEMBER(grey.psf_sigma_voxels), "(0, 8]", "voxels",
                        "the scanner's point spread (Gaussian sigma): the apertures' window "
                        "reaches three of it past the sheet"));
  {
    ParamRow r = Row("grey.scales", ParamType::kNumbers, "(0, 16]", "voxels",
                     "Gaussian scales of the sheetness filter");
    r.spec.max_count = 8;  // a filter pass over the volume each (10,000 ran for minutes)
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      return ParamValue(o.grey.sheetness.scales);
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      o.grey.sheetness.scales = std::get<std::vector<double>>(v);
    };
    r.check = [](const ParamValue& v) -> std::string {
      return std::get<std::vector<double>>(v).empty() ? "must hold at least one scale" : "";
    };
    rows.push_back(std::move(r));
  }
  rows.push_back(Number("grey.high", SM_MEMBER(grey.sheetness.high), "(0, 1000]", "",
                        "sheetness that seeds a sheet, in units of its noise (the median "
                        "response)"));
  rows.push_back(Number("grey.low", SM_MEMBER(grey.sheetness.low), "(0, 1000]", "",
                        "sheetness a sheet grows through from its seeds, in the same units"));
  return rows;
}

// Formula 4 (§2.2.2) for one of the two modes.
void AddExtendRows(const std::string& step, const std::string& what,
                   ExtendOptions ExtractionOptions::*member, bool ExtractionOptions::*enabled,
                   const char* max_rounds, std::vector<ParamRow>* rows) {
  auto ref = [member](PipelineOptions& o) -> ExtendOptions& { return o.extraction.*member; };
  rows->push_back(Bool(
      step + ".enabled", [enabled](PipelineOptions& o) -> bool& { return o.extraction.*enabled; },
      what));
  const bool front = step == "recover";  // regrow.h: a front, a voxel per round
  rows->push_back(Number(
      step + ".t", [ref](PipelineOptions& o) -> double& { return ref(o).half_thickness_voxels; },
      front ? "(0, 100]" : "0 | (0, 100]", "voxels",
      front ? "t of formula 4: the least half-thickness of a cell's plane (each "
              "cell takes half its thickest run plus half a voxel when more)"
            : "t of formula 4: half-thickness of the extension's flat cylinder (0: 0.3 "
              "separate.r, 1.5 at r = 5)"));
  if (!front) {
    rows->push_back(Number(
        step + ".R", [ref](PipelineOptions& o) -> double& { return ref(o).radius_voxels; },
        "0 | (0, 1000]", "voxels",
        "R of formula 4: radius of the extension's flat cylinder (0: 1.4 separate.r, 7 at r "
        "= 5)"));
  }
  rows->push_back(Integer(
      step + ".rounds", [ref](PipelineOptions& o) -> int& { return ref(o).max_rounds; }, max_rounds,
      "",
      front ? "rounds of the growing front at most (0: until nothing is added)"
            : "rebuild-and-extend rounds at most"));
  rows->push_back(Number(
      step + ".scvd_r", [ref](PipelineOptions& o) -> double& { return ref(o).scvd_radius_voxels; },
      "0 | (0, 1000]", "voxels",
      "r of the SCVD whose triangles give the extension's normals (0: separate.r)"));
}

std::vector<ParamRow> ExtractionRows() {
  std::vector<ParamRow> rows;
  rows.push_back(
      Bool("extract", SM_MEMBER(extract), "run the feature extraction of Fig. 3 before meshing"));
  rows.push_back(Integer("M", SM_MEMBER(extraction.min_object_voxels), "[0, 1e15]", "voxels",
                         "objects and pieces with fewer voxels are minor and go (0: three "
                         "separation cells, 3 t(1 + 2 r (r - 1)))"));
  rows.push_back(Bool("refine.enabled", SM_MEMBER(extraction.refine),
                      "refine the phase by a closing and an opening (§2.2.1)"));
  rows.push_back(Integer("refine.close_radius", SM_MEMBER(extraction.refine_close_radius),
                         "[0, 50]", "voxels",
                         "closing radius (0: none; a closing adds voxels the image does not "
                         "have, which the similarity against the raw phase counts against it)"));
  rows.push_back(Integer("refine.open_radius", SM_MEMBER(extraction.refine_open_radius), "[0, 50]",
                         "voxels",
                         "opening radius (0: none; it erases sheets thinner than twice it)"));
  AddExtendRows("detect", "detect potential objects by extending into empty space (Fig. 6)",
                &ExtractionOptions::detect_extend, &ExtractionOptions::detect, "[0, 100]", &rows);
  rows.push_back(Bool("separate.enabled", SM_MEMBER(extraction.separate),
                      "separate crossing sheets (Algorithm 2)"));
  rows.push_back(Number("separate.r", SM_MEMBER(extraction.separation.radius_voxels),
                        "0 | (0, 1000]", "voxels",
                        "r of the SCVD built for separation (0: max(5, t/2) with t the sheet "
                        "phase's mean thickness; the report's extraction.scale says which)"));
  rows.push_back(Number("separate.D_ang", SM_MEMBER(extraction.separation.dihedral_degrees),
                        "(90, 180)", "degrees",
                        "D_ang: two triangles meeting below this dihedral angle are not flat"));
  rows.push_back(Integer("separate.widen_rings", SM_MEMBER(extraction.separation.widen_rings),
                         "[0, 5]", "",
                         "a piece that leaked through a missed cell is flooded again with the "
                         "non-flat set widened by this many mesh edges (0: the paper)"));
  rows.push_back(Integer("separate.fit_rings", SM_MEMBER(extraction.separation.fit_rings), "[0, 5]",
                         "",
                         "a fold of two triangles cuts only where the generators within this "
                         "many mesh edges do not fit one plane, so a rough or thick sheet is "
                         "not cut (0: the paper, every fold cuts)"));
  rows.push_back(Bool("remove_minor.enabled", SM_MEMBER(extraction.remove_minor),
                      "remove the pieces with fewer than M voxels"));
  AddExtendRows("recover", "recover the gaps separation cut, extending within the image (Fig. 7)",
                &ExtractionOptions::recover_extend, &ExtractionOptions::recover, "[0, 100000]",
                &rows);
  return rows;
}

std::vector<ParamRow> SurfaceRows() {
  std::vector<ParamRow> rows;
  rows.push_back(Number("r", SM_MEMBER(surface.scvd.radius_voxels), "(0, 4096]", "voxels",
                        "SCVD cell radius r of formula 3: the one size parameter"));
  {
    ParamRow r = Row("target_similarity", ParamType::kNumber, "(0, 1)", "",
                     "search the largest r whose similarity reaches this (paper: 0.6; unset: "
                     "no search)");
    r.spec.exclusive = "radius search";
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      if (!o.search_radius || o.radius_search.goal != RadiusGoal::kTargetSimilarity) {
        return std::nullopt;
      }
      return ParamValue(o.radius_search.target_similarity);
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      o.search_radius = true;
      o.radius_search.goal = RadiusGoal::kTargetSimilarity;
      o.radius_search.target_similarity = std::get<double>(v);
    };
    rows.push_back(std::move(r));
  }
  {
    ParamRow r = Row("triangles", ParamType::kInteger, "[1, 1e9]", "",
                     absl::StrCat("search the r whose mesh has this many triangles, within ",
                                  100 * kTriangleTolerance, "% (unset: r as given)"));
    r.spec.exclusive = "radius search";
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      if (!o.search_radius || o.radius_search.goal != RadiusGoal::kTriangles) return std::nullopt;
      return ParamValue(int64_t(o.radius_search.triangles));
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      o.search_radius = true;
      o.radius_search.goal = RadiusGoal::kTriangles;
      o.radius_search.triangles = uint64_t(std::get<int64_t>(v));
    };
    rows.push_back(std::move(r));
  }
  {
    ParamRow r =
        Row("search_best", ParamType::kBool, nullptr, "", "search the r of the best similarity");
    r.spec.exclusive = "radius search";
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      return ParamValue(o.search_radius && o.radius_search.goal == RadiusGoal::kBestSimilarity);
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      if (std::get<bool>(v)) {
        o.search_radius = true;
        o.radius_search.goal = RadiusGoal::kBestSimilarity;
      } else if (o.radius_search.goal == RadiusGoal::kBestSimilarity) {
        o.search_radius = false;
      }
    };
    rows.push_back(std::move(r));
  }
  rows.push_back(Bool("surface.decimate", SM_MEMBER(radius_search.decimate),
                      "with triangles: mesh about 4 times as many, then merge the flattest "
                      "(quadric edge collapses) down to the count (false: r alone)"));
  rows.push_back(Number("radius_search.r_min", SM_MEMBER(radius_search.min_radius_voxels),
                        "(0, 4096]", "voxels", "smallest r a search tries"));
  rows.push_back(Number("radius_search.r_max", SM_MEMBER(radius_search.max_radius_voxels),
                        "0 | (0, 4096]", "voxels",
                        "largest r a search tries (0: a quarter of the largest extent)"));
  {
    ParamRow r = Row("surface.method", ParamType::kChoice, nullptr, "",
                     "a preset of the surface settings: extended (rim strip, centroid vertices, "
                     "thickness along the normal) or paper (the plain reading)");
    r.spec.choices = {"extended", "paper"};
    r.spec.preset = true;
    r.get = [](const PipelineOptions&) -> std::optional<ParamValue> { return std::nullopt; };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      const SurfaceOptions p =
          std::get<std::string>(v) == "paper" ? SurfaceOptions::Paper() : SurfaceOptions();
      o.surface.placement = p.placement;
      o.surface.thickness = p.thickness;
      o.surface.dual.rim = p.dual.rim;
      o.surface.dual.close_cracks = p.dual.close_cracks;
      o.surface.scvd.domain = p.scvd.domain;
    };
    rows.push_back(std::move(r));
  }
  rows.push_back(Integer("surface.seed", SM_MEMBER(surface.scvd.seed), "[0, 9007199254740992]", "",
                         "seed of the generators' random choice"));
  rows.push_back(Bool("surface.local_seeding", SM_MEMBER(surface.scvd.local),
                      "generators drawn on a grid fixed in the volume (each cube's count "
                      "rounded by a hash of it, placed by a hash of position, a cell's radius "
                      "apart), ids in position order and exactly lloyd_max_iter Lloyd steps, so "
                      "a brick with a halo builds its core's cells as the whole volume does"));
  rows.push_back(Integer("surface.bricks", SM_MEMBER(surface.bricks.brick), "[0, 1e6]", "voxels",
                         "build the SCVD and its triangles in bricks of this side with halos, "
                         "checked and joined at their seams (0: the whole sheet at once); at "
                         "least 32, the halo, and 4 r + the sheet's thickest run"));
  rows.push_back(Integer("surface.bricks_halo", SM_MEMBER(surface.bricks.halo), "[0, 1e6]",
                         "voxels",
                         "with surface.bricks: voxels read around each brick (0: from r and the "
                         "longest thickness run, doubled where the seams disagree)"));
  rows.push_back(Integer("surface.generators", SM_MEMBER(surface.scvd.generator_count), "[0, 1e12]",
                         "", "total generators instead of formula 3 (0: formula 3)"));
  rows.push_back(Number("surface.thickness", SM_MEMBER(surface.scvd.mean_thickness_voxels),
                        "[0, 10000]", "voxels", "mean thickness t of formula 3 (0: measured)"));
  rows.push_back(Integer("surface.lloyd_max_iter", SM_MEMBER(surface.scvd.lloyd_max_iter),
                         "[0, 1000]", "", "Lloyd steps at most"));
  rows.push_back(Number("surface.lloyd_tol", SM_MEMBER(surface.scvd.lloyd_tol), "[0, 1]", "",
                        "Lloyd stops when the energy changes by less (relative)"));
  rows.push_back(Choice("surface.domain", SM_MEMBER(surface.scvd.domain),
                        {{"voxels", ScvdDomain::kVoxels},
                         {"columns", ScvdDomain::kColumns},
                         {"auto", ScvdDomain::kAuto}},
                        "what the SCVD grows over: voxels, columns across the thickness, or auto "
                        "(columns where cells would stack)"));
  rows.push_back(Choice("surface.mesher", SM_MEMBER(surface.method),
                        {{"scvd", SurfaceMethod::kScvd},
                         {"midsurface", SurfaceMethod::kMid},
                         {"auto", SurfaceMethod::kAuto}},
                        "how a sheet's triangles are made: the SCVD's dual triangles (the "
                        "paper), or its mid-surface at voxel resolution with the aperture, "
                        "decimated to the triangles r (or surface.triangles) gives, its "
                        "junctions at the rock's angles; auto: both, the mid-surface kept "
                        "unless it scores more than 0.01 below the SCVD's"));
  rows.push_back(
      Choice("surface.placement", SM_MEMBER(surface.placement),
             {{"generator", VertexPlacement::kGenerator}, {"centroid", VertexPlacement::kCentroid}},
             "mesh vertices at the generators' voxels or their cells' centroids"));
  rows.push_back(
      Choice("surface.thickness_measure", SM_MEMBER(surface.thickness),
             {{"axis_runs", ThicknessMeasure::kAxisRuns}, {"normal", ThicknessMeasure::kNormal}},
             "triangle thickness from the shortest axis run, or along the normal"));
  rows.push_back(Bool("surface.fit_walls", SM_MEMBER(surface.fit_walls),
                      "fit each face's thickness to the best formula-5 score of the prisms "
                      "together (false: the mean τ of the voxels it passes through)"));
  rows.push_back(
      Choice("surface.fit_vertices", SM_MEMBER(surface.fit_vertices),
             {{"auto", VertexFit::kAuto},
              {"none", VertexFit::kNone},
              {"rim", VertexFit::kRim},
              {"all", VertexFit::kAll}},
             "with fit_walls, vertices moved where formula 5 of the prisms rises: rim, rims across "
             "themselves and onto a face of the box within 1.5 voxels; all, every vertex along its "
             "normal too; auto: rim, or none with volume_mesh (the moves cost the volume mesh "
             "angles); junctions stay"));
  rows.push_back(Number("surface.error_density", SM_MEMBER(surface.error_density), "[0, 100]", "",
                        "> 0: a second SCVD whose density ρ (formula 2) rises by this much where "
                        "the first surface misses the sheet; the better by formula 5 is kept"));
  rows.push_back(Integer("surface.smooth", SM_MEMBER(surface.smooth_iterations), "[0, 1000]", "",
                         "λ|μ smoothing steps of the mid-surface where the sheet is thicker than "
                         "its triangles are wide (0: none)"));
  rows.push_back(Number("surface.rim_push", SM_MEMBER(surface.dual.rim_push_voxels), "[0, 1]",
                        "voxels",
                        "rim vertices this far past the outermost voxels' centres (0.5: at the "
                        "voxels' edge, a closer rim; 0: the volume mesh keeps larger angles)"));
  rows.push_back(Bool("surface.rim", SM_MEMBER(surface.dual.rim),
                      "close the band along the rims with a strip of triangles"));
  rows.push_back(Bool("surface.close_cracks", SM_MEMBER(surface.dual.close_cracks),
                      "close narrow notches the triangle selection leaves in the boundary"));
  rows.push_back(Choice("surface.representation", SM_MEMBER(representation.mode),
                        {{"auto", RepresentationMode::kAuto},
                         {"sheet", RepresentationMode::kSheet},
                         {"body", RepresentationMode::kBody}},
                        "each piece as a sheet (one layer of triangles with thickness), a body "
                        "(the closed surface around it, a region of the volume mesh) or auto: "
                        "whichever scores better with the piece's share of the triangles, "
                        "bodies only as thick as the next two say (a thin piece is a sheet with "
                        "its aperture)"));
  rows.push_back(Number("surface.body_min_thickness", SM_MEMBER(representation.body_min_thickness),
                        "[0, 10000]", "voxels",
                        "in auto, a piece thinner than this (median thickness) stays a sheet "
                        "without a trial as a body"));
  rows.push_back(Number("surface.body_min_aspect", SM_MEMBER(representation.body_min_aspect),
                        "[0, 100]", "",
                        "in auto, a piece or a lens of one is tried as a body only where its "
                        "median thickness is at least this fraction of its width"));
  rows.push_back(Bool("surface.thin_bodies", SM_MEMBER(representation.try_thin_bodies),
                      "in auto where the surface is the result (no volume mesh, no --grey), try "
                      "thin pieces as bodies too and keep whichever scores better (a body has no "
                      "aperture)"));
  rows.push_back(Number(
      "surface.fold_angle", SM_MEMBER(surface.dual.fold_angle_degrees), "[0, 180)", "degrees",
      "a candidate meeting a kept triangle below this dihedral angle is refused"));
  return rows;
}

std::vector<ParamRow> SimilarityRows() {
  std::vector<ParamRow> rows;
  {
    ParamRow r = Row("similarity.model", ParamType::kChoice, nullptr, "",
                     "prisms of one thickness per triangle (face) or a linear shell (vertex)");
    r.spec.choices = {"face", "vertex"};
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      return ParamValue(std::string(o.score.height == PrismHeight::kVertex ? "vertex" : "face"));
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      o.score.height =
          std::get<std::string>(v) == "vertex" ? PrismHeight::kVertex : PrismHeight::kFace;
      o.radius_search.height = o.score.height;   // a search scores with the same model
      o.representation.height = o.score.height;  // and so does the choice of a piece's
    };
    rows.push_back(std::move(r));
  }
  rows.push_back(Bool("similarity.hausdorff", SM_MEMBER(score.hausdorff),
                      "also the symmetric Hausdorff distance"));
  {
    ParamRow r = Row("similarity.grid_rates", ParamType::kIntegers, "[1, 64]", "",
                     "grid-model baselines of Table 2 to score (empty: none)");
    r.spec.allow_empty = true;
    r.get = [](const PipelineOptions& o) -> std::optional<ParamValue> {
      return ParamValue(std::vector<int64_t>(o.score.grid_rates.begin(), o.score.grid_rates.end()));
    };
    r.set = [](const ParamValue& v, PipelineOptions& o) {
      const auto& k = std::get<std::vector<int64_t>>(v);
      o.score.grid_rates.assign(k.begin(), k.end());
    };
    rows.push_back(std::move(r));
  }
  return rows;
}

#undef SM_MEMBER

}  // namespace

const std::vector<ParamRow>& ParamRows() {
  static const std::vector<ParamRow>* rows = [] {
    auto* all = new std::vector<ParamRow>;
    for (auto part : {InputRows(), GreyRows(), ExtractionRows(), SurfaceRows(), SimilarityRows(),
                      VolumeMeshRows(), FlowRows(), OutputRows()}) {
      for (ParamRow& r : part) all->push_back(std::move(r));
    }
    return all;
  }();
  return *rows;
}

}  // namespace sheetmesh
