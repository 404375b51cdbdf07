// Pipeline parameters on the `sheetmesh` command line: every field of PipelineParameters
// and of the input's VolumeFormat is a flag of the same name (`--separate_r=6`,
// `--separate.r 6`, `--labels=2,3`, `--dims=64x64x32`, `--volume_mesh`, `--noextract`),
// set by proto reflection, so the client needs no list of its own. The names are the
// pipeline's parameter table's (sheetmesh-pipeline params); the server checks the values.
#ifndef SHEETMESH_CLIENT_PARAMETER_FLAGS_H_
#define SHEETMESH_CLIENT_PARAMETER_FLAGS_H_

#include <vector>

#include "absl/status/statusor.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::client {

// Sets the fields named by parameter flags in `parameters` and `format` and returns argv
// without them (argv[0] first). kInvalidArgument naming the flag for text that is not of
// the field's type.
absl::StatusOr<std::vector<char*>> TakeParameterFlags(int argc, char** argv,
                                                      v1::PipelineParameters* parameters,
                                                      v1::VolumeFormat* format);

}  // namespace sheetmesh::client

#endif  // SHEETMESH_CLIENT_PARAMETER_FLAGS_H_
