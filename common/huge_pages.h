// Start-up tuning for processes that hold large arrays or stream large messages: ask
// glibc's malloc for transparent huge pages, and to keep freed memory for reuse instead of
// handing it back to the kernel at once. On virtual machines a page fault costs more than
// the work on sparse voxels, or than copying a network buffer.
#ifndef SHEETMESH_COMMON_HUGE_PAGES_H_
#define SHEETMESH_COMMON_HUGE_PAGES_H_

namespace sheetmesh {

// If the environment does not set glibc.malloc.hugetlb yet, sets it to 1, with
// glibc.malloc.mmap_threshold = 64 MiB and glibc.malloc.trim_threshold = 256 MiB (blocks
// below 64 MiB come from the heap and are reused; at most 256 MiB of free heap is kept),
// and re-executes the program with the same arguments (glibc reads tunables only at
// start-up). Tunables already in GLIBC_TUNABLES are kept. Returns normally when nothing
// needs doing, when SHEETMESH_NO_HUGE_PAGES is set, or when the re-exec fails. Call first
// thing in main(), before any thread starts. `max_arenas` > 0 also caps glibc's malloc
// arenas (glibc.malloc.arena_max): a server whose network threads allocate message buffers
// that other threads free otherwise spreads free memory over one arena per thread, and its
// resident size creeps up with the bytes streamed.
void UseTransparentHugePages(int argc, char** argv, int max_arenas = 0);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_HUGE_PAGES_H_
