// What the HDF5 reader and writer share: an id that closes itself, and the library's error
// printing turned off (errors come back as statuses naming the file).
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_HDF5_INTERNAL_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_HDF5_INTERNAL_H_

#include <hdf5.h>

namespace sheetmesh::hdf5_internal {

// An HDF5 id closed by `close` on destruction.
class H5Id {
 public:
  H5Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;
  H5Id(H5Id&& o) noexcept : id_(o.release()), close_(o.close_) {}
  ~H5Id() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  // Gives the id up: it is no longer closed here.
  hid_t release() {
    const hid_t id = id_;
    id_ = -1;
    return id;
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

inline void QuietErrors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

}  // namespace sheetmesh::hdf5_internal

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_HDF5_INTERNAL_H_
