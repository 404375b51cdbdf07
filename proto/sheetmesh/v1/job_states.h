// Whether a job state ends a job: the one test of it for every C++ layer that sees the
// protos (the server, the runtime, the clients).
#ifndef SHEETMESH_PROTO_SHEETMESH_V1_JOB_STATES_H_
#define SHEETMESH_PROTO_SHEETMESH_V1_JOB_STATES_H_

#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::v1 {

// SUCCEEDED, FAILED or CANCELLED: the job has ended and will not change again.
inline bool IsTerminal(JobState state) {
  return state == SUCCEEDED || state == FAILED || state == CANCELLED;
}

}  // namespace sheetmesh::v1

#endif  // SHEETMESH_PROTO_SHEETMESH_V1_JOB_STATES_H_
