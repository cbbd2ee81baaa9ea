// libFuzzer target: the model loader's input checks (`--model FILE.obj`): the coordinate check,
// then assimp, then liveprobe's own checks of what assimp returns. Any input ends in a mesh
// whose positions are finite and whose indices are in range, or in lp::MeshError.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "liveprobe/gl/mesh.h"
#include "temp_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = writeFuzzInput("model", ".obj", data, size);
  try {
    const lp::Mesh m = lp::loadMesh(path);
    for (const auto& p : m.positions)
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
    for (auto i : m.indices)
      if (i >= m.positions.size()) std::abort();
    if (m.normals.size() != m.positions.size()) std::abort();
  } catch (const lp::MeshError&) {
  }
  std::remove(path.c_str());
  return 0;
}
