// The named phantoms: each kind of fracture the tests and benchmarks need a known answer
// for, with its ground truth written beside it (PhantomTruth::ToJson).
#ifndef SHEETMESH_WORKER_PIPELINE_PHANTOM_PHANTOM_PRESETS_H_
#define SHEETMESH_WORKER_PIPELINE_PHANTOM_PHANTOM_PRESETS_H_

#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/pipeline/phantom/phantom.h"

namespace sheetmesh {

// sample         128x112x96: three crossing rough sheets (aperture 4) with holes, one cut
//                into fragments, and specks; the demo's volume.
// paper          1012x1024x931: six crossing sheets and a speck per 20^3 voxels, the
//                paper's scale.
// thick_slab     100x100x111: one near-horizontal slab 30-50 voxels thick (mean 40) with
//                rough walls (4 voxels), crossing the whole box: a dissolution-widened
//                fracture.
// rough_network  160^3: four rough crossing sheets of radius 36-54, aperture 3.2-6.8
//                along each, two holes each, and 200 specks.
absl::StatusOr<PhantomOptions> PhantomPreset(std::string_view name);

// The names above, in that order.
std::vector<std::string> PhantomPresetNames();

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_PHANTOM_PHANTOM_PRESETS_H_
