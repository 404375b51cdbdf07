// An RGB picture in memory, for the previews and their legends.
#ifndef SHEETMESH_WORKER_PIPELINE_PREVIEW_RGB_IMAGE_H_
#define SHEETMESH_WORKER_PIPELINE_PREVIEW_RGB_IMAGE_H_

#include <array>
#include <cstdint>
#include <vector>

namespace sheetmesh {

// An RGB picture, rows top to bottom.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // 3 * width * height

  void Set(int x, int y, const std::array<uint8_t, 3>& c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    uint8_t* p = &rgb[3 * (static_cast<size_t>(y) * width + x)];
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
  }
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_PREVIEW_RGB_IMAGE_H_
