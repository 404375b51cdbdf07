// Internal to the TIFF reader and writer: libtiff's messages as Status text, and TIFF
// handles that close themselves.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_TIFF_INTERNAL_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_TIFF_INTERNAL_H_

#include <tiffio.h>

#include <memory>
#include <string>

namespace sheetmesh::tiff_internal {

// Routes libtiff's errors to LastTiffError (and drops its warnings); idempotent.
void InstallTiffHandlersOnce();
// The last libtiff error of this thread (cleared by the call).
std::string LastTiffError();

struct TiffCloser {
  void operator()(TIFF* t) const {
    if (t != nullptr) TIFFClose(t);
  }
};
using TiffPtr = std::unique_ptr<TIFF, TiffCloser>;

}  // namespace sheetmesh::tiff_internal

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_TIFF_INTERNAL_H_
