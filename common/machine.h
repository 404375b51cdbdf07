// What the machine has: its physical memory, for the defaults that are fractions of it.
#ifndef SHEETMESH_COMMON_MACHINE_H_
#define SHEETMESH_COMMON_MACHINE_H_

#include <unistd.h>

#include <cstdint>

namespace sheetmesh {

// The machine's physical memory in bytes, or `fallback` when the system does not say.
inline uint64_t PhysicalMemoryBytes(uint64_t fallback) {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return fallback;
  return static_cast<uint64_t>(pages) * static_cast<uint64_t>(page);
}

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_MACHINE_H_
